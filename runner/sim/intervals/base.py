"""The interval state machine every leaf shares: ``CInterval``'s default ``priv_*`` methods.

Panda3D drives an interval through ``priv_initialize(t)``, ``priv_step(t)``, ``priv_finalize()``,
``priv_instant()`` (begin and end within one frame), their ``reverse`` twins (time going backwards,
e.g. a restarted Sequence rewinding to 0) and ``priv_interrupt()`` (pause). The defaults here are
``direct/src/interval/cInterval.cxx`` (identical to ``Interval.py`` for Python intervals); leaves
override what they need. Every call carries ``at``: the simulated time of the event, passed to the
host when the leaf fires an action or a sound.

Time constants: meta intervals compare times as integer milliseconds, ``floor(t*1000 + 0.5)``
(``CMetaInterval::double_to_int_time``, config ``interval-precision`` 1000). Play time
``t = (now - clock_start)*rate + start_t`` is a float; :data:`TIME_EPS` (1 ns) absorbs the rounding
of float clocks, so that 50 steps of 0.04 s reach the end of a 2.0 s interval (Panda3D itself gives
either outcome, depending on its clock's last bits).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from typing import Final

__all__ = ["PRECISION", "TIME_EPS", "Ev", "Node", "State", "from_ms", "to_ms"]

#: tolerance on play time, seconds (see the module docstring)
TIME_EPS: Final = 1e-9
#: meta-interval time precision, ticks per second (``interval-precision``)
PRECISION: Final = 1000.0


def to_ms(t: float) -> int:
    """``CMetaInterval::double_to_int_time``."""
    return math.floor(t * PRECISION + 0.5)


def from_ms(ticks: int) -> float:
    """``CMetaInterval::int_to_double_time``."""
    return ticks / PRECISION


class State(enum.IntEnum):
    """``CInterval::State``."""

    INITIAL = 0
    STARTED = 1
    PAUSED = 2
    FINAL = 3


class Ev(enum.IntEnum):
    """``CInterval::EventType``: what a meta interval asks of a child."""

    INITIALIZE = 0
    INSTANT = 1
    STEP = 2
    FINALIZE = 3
    REVERSE_INITIALIZE = 4
    REVERSE_INSTANT = 5
    REVERSE_FINALIZE = 6
    INTERRUPT = 7


class Node:
    """One Panda3D interval object: state, current t and the default ``priv_*`` behaviour."""

    #: a Python interval (``Interval.Interval``: Func, SoundInterval); False for C++ ones (Lerp, Wait, meta)
    is_python: bool = False
    #: run when skipped entirely by a finish/initialize (``open_ended``; Func, Lerp, Wait, meta: True)
    open_ended: bool = True

    def __init__(self, duration: float) -> None:
        self.duration = max(duration, 0.0)
        self.state = State.INITIAL
        self.curr_t = 0.0
        #: set on a top-level interval: called where Panda3D's ``interval_done()`` throws the done event
        self.on_done: Callable[[float], None] | None = None

    def is_stopped(self) -> bool:
        return self.state == State.INITIAL or self.state == State.FINAL

    def interval_done(self, at: float) -> None:
        if self.on_done is not None:
            self.on_done(at)

    def on_setup_play(self, do_loop: bool) -> None:
        """Called by ``setup_play`` when this node is a top-level interval (SoundInterval uses it)."""

    def priv_initialize(self, t: float, at: float) -> None:
        self.state = State.STARTED
        self.priv_step(t, at)

    def priv_instant(self, at: float) -> None:
        self.state = State.STARTED
        self.priv_step(self.duration, at)
        self.state = State.FINAL
        self.interval_done(at)

    def priv_step(self, t: float, at: float) -> None:
        self.state = State.STARTED
        self.curr_t = t

    def priv_finalize(self, at: float) -> None:
        self.priv_step(self.duration, at)
        self.state = State.FINAL
        self.interval_done(at)

    def priv_reverse_initialize(self, t: float, at: float) -> None:
        self.state = State.STARTED
        self.priv_step(t, at)

    def priv_reverse_instant(self, at: float) -> None:
        self.state = State.STARTED
        self.priv_step(0.0, at)
        self.state = State.INITIAL

    def priv_reverse_finalize(self, at: float) -> None:
        self.priv_step(0.0, at)
        self.state = State.INITIAL

    def priv_interrupt(self, at: float) -> None:
        self.state = State.PAUSED

    def do_event(self, ev: Ev, t: float, at: float) -> None:
        """``CInterval::priv_do_event``."""
        if ev == Ev.STEP:
            self.priv_step(t, at)
        elif ev == Ev.INITIALIZE:
            self.priv_initialize(t, at)
        elif ev == Ev.INSTANT:
            self.priv_instant(at)
        elif ev == Ev.FINALIZE:
            self.priv_finalize(at)
        elif ev == Ev.INTERRUPT:
            self.priv_interrupt(at)
        elif ev == Ev.REVERSE_INITIALIZE:
            self.priv_reverse_initialize(t, at)
        elif ev == Ev.REVERSE_INSTANT:
            self.priv_reverse_instant(at)
        else:
            self.priv_reverse_finalize(at)
