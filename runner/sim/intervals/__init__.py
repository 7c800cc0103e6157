"""Panda3D interval semantics, headless: lerps, Sequence/Parallel, Func, SoundInterval, ivalMgr.

The runner compiles a scenario's intervals to the specs of :mod:`.specs`, implements
:class:`IntervalHost` and drives one :class:`IntervalManager` with the simulated clock: ``start``,
``pause``, ``resume``, ``finish`` and ``loop`` from handlers, then ``step(now)`` once per scenario step.
The behaviour is Panda3D 1.10's (see ``/work/shared/notes/panda3d-semantics.md`` sections 1-3),
including same-name takeover and name-ordered stepping.
"""

from __future__ import annotations

from runner.compile.interval_specs import (
    BLEND_TYPES,
    FuncSpec,
    IntervalSpec,
    LerpSpec,
    ParallelSpec,
    SequenceSpec,
    SoundSpec,
    Vec3,
    WaitSpec,
)
from runner.sim.intervals.base import PRECISION, TIME_EPS
from runner.sim.intervals.host import IntervalHost
from runner.sim.intervals.lerp import compute_delta
from runner.sim.intervals.manager import IntervalManager

__all__ = [
    "BLEND_TYPES",
    "FuncSpec",
    "IntervalHost",
    "IntervalManager",
    "IntervalSpec",
    "LerpSpec",
    "PRECISION",
    "ParallelSpec",
    "SequenceSpec",
    "SoundSpec",
    "TIME_EPS",
    "Vec3",
    "WaitSpec",
    "compute_delta",
]
