"""Condition triggers: an event raised when a condition becomes true (docs/language.md, "Triggers").

Edge-triggered, like OpenSCENARIO's rising edge: a trigger fires at a recorded state where its condition is
true and was false at the previous one (the state at t=0 only sets the first previous value, so a condition
already true at the start fires only after it has been false). It is checked after every step, once the
state is read and contacts are detected; its event is queued behind that step's collision events and
delivered at the start of the next step, stamped with the time of the state that raised it. By default a
trigger is re-armed when its condition is false again; ``once: true`` fires it at most once.

Also here: handlers that run once or not within a minimum interval, and reading joint coordinates from a
stated zero (``limits: {zero: absolute}``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from backends.types import JointStates
from runner.compile.program import HandlerSpec, TriggerSpec
from runner.language.expressions import Expression, Resolver


class ConditionTriggers:
    """The triggers of a run and their previous values."""

    def __init__(self, triggers: Sequence[TriggerSpec], expressions: dict[str, Expression]) -> None:
        self.triggers = [(t, expressions[t.when]) for t in triggers]
        self.previous = [True] * len(self.triggers)  # until start(): nothing fires before the first state
        self.spent = [False] * len(self.triggers)

    def start(self, resolver: Resolver) -> None:
        """The conditions at t=0: the first previous values."""
        self.previous = [expr.truth(resolver) for _, expr in self.triggers]

    def check(self, resolver: Resolver) -> list[str]:
        """The events raised by the state just read, in the order the triggers are written."""
        raised = []
        for i, (trigger, expr) in enumerate(self.triggers):
            if self.spent[i]:
                continue
            now = expr.truth(resolver)
            if now and not self.previous[i]:
                raised.append(trigger.event)
                self.spent[i] = trigger.once
            self.previous[i] = now
        return raised


class HandlerGate:
    """Whether a handler runs for a delivery of its event: `once` and `min_interval` (docs/language.md)."""

    def __init__(self) -> None:
        self.last: dict[str, float] = {}  # event -> when its handler last ran

    def refusal(self, event: str, handler: HandlerSpec, at: float) -> str | None:
        """None if the handler runs now (and this run is remembered), else why it does not."""
        last = self.last.get(event)
        if last is not None and (handler.once or (handler.min_interval or 0.0) > at - last + 1e-9):
            why = "once" if handler.once else f"min_interval {handler.min_interval:g} s"
            return f"handler for {event} not run ({why}; it last ran at t={last:.4f})"
        self.last[event] = at
        return None


def with_zeros(joints: JointStates, zeros: Sequence[tuple[int, float]] | JointZeros) -> JointStates:
    """``joints`` with the positions of the given joints shifted by their zero offsets (itself if none)."""
    if not isinstance(zeros, JointZeros):
        zeros = JointZeros(zeros)
    if not zeros.rows.size:
        return joints
    position = joints.position.copy()
    position[zeros.rows] += zeros.offsets  # each reading plus its offset: one whole-array call
    return JointStates(position, joints.velocity, joints.motor_force)


class JointZeros:
    """(joint index, offset) pairs as two arrays, made once for ``with_zeros`` every step (distinct joints)."""

    def __init__(self, zeros: Sequence[tuple[int, float]]) -> None:
        self.rows = np.array([k for k, _ in zeros], dtype=np.int64)
        self.offsets = np.array([offset for _, offset in zeros], dtype=float)
