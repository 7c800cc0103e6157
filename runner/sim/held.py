"""Held forces (the `apply` action): a force and torque the runner hands the engine on every step a while.

An `apply` run by a handler during step k (at t_k) acts on steps k, k+1, ... : before each of them, with the
states read at its start, it is turned into a world-frame force at the centre of mass and a torque, and
given to the engine as that step's force (``Backend.apply_force``, which holds it over every substep).
`frame: body` turns the vectors with the body's orientation at the step's start; a force `at` a point p of
the body adds the torque R (p - com) x F. It stops after round(`for` / dt) steps (at least one), or at the
first step whose start finds `until` true (checked before the step, the first one included).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from runner.language.model_actions import ApplyCommand


@dataclass
class Held:
    """A force or torque held on a body, for a number of steps or until a condition holds."""

    body: int
    command: ApplyCommand
    steps_left: int | None  # None: until the condition holds


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` turned by the unit quaternion ``q`` (w, x, y, z)."""
    w, u = q[0], q[1:]
    return np.asarray(v + 2.0 * np.cross(u, np.cross(u, v) + w * v), dtype=float)


class HeldForces:
    """The `apply` actions acting now, in the order they were started."""

    def __init__(self, dt: float, coms: list[tuple[float, float, float]]) -> None:
        self.dt = dt
        self.coms = np.asarray(coms, dtype=float).reshape(-1, 3)  # each body's COM in its frame
        self.active: list[Held] = []

    def __bool__(self) -> bool:
        return bool(self.active)

    def start(self, body: int, command: ApplyCommand) -> int | None:
        """Start a held force; the number of steps it lasts (None: until its condition)."""
        steps = None if command.for_ is None else max(1, round(command.for_ / self.dt))
        self.active.append(Held(body, command, steps))
        return steps

    def step_inputs(
        self, quats: np.ndarray, truth: Callable[[str], bool]
    ) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """This step's (body, world force, world torque) of every held force still acting; those that end
        before this step are dropped."""
        out = []
        still = []
        for held in self.active:
            c = held.command
            if held.steps_left is not None:
                if held.steps_left <= 0:
                    continue
                held.steps_left -= 1
            elif c.until is not None and truth(c.until):
                continue
            still.append(held)
            force, torque = np.asarray(c.force, float), np.asarray(c.torque, float)
            q = np.asarray(quats[held.body], float)
            if c.frame == "body":
                force, torque = _rotate(q, force), _rotate(q, torque)
            if c.at is not None:
                arm = _rotate(q, np.asarray(c.at, float) - self.coms[held.body])
                torque = torque + np.cross(arm, force)
            out.append((held.body, force, torque))
        self.active = [h for h in still if h.steps_left is None or h.steps_left > 0]
        return out
