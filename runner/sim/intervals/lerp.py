"""Lerp blending and the C++ leaves: ``CLerpNodePathInterval`` and ``WaitInterval``.

Sources: ``direct/src/interval/cLerpInterval.cxx`` (``compute_delta``), ``lerp_helpers.h``
(``lerp_value``) and ``cLerpNodePathInterval.cxx`` (``priv_step`` and the bake-in of start values).
Panda3D computes positions in single precision (``LPoint3f``); this module uses doubles.
"""

from __future__ import annotations

from typing import Final

from runner.compile.interval_specs import BLEND_TYPES, LerpSpec, Vec3
from runner.sim.intervals.base import Node, State
from runner.sim.intervals.host import IntervalHost

__all__ = ["LerpLeaf", "WaitLeaf", "compute_delta", "lerp_value", "lerp_vec3"]

_NO_BLEND: Final = 0
_EASE_IN: Final = 1
_EASE_OUT: Final = 2
_EASE_IN_OUT: Final = 3
_BLEND_CODES: Final = {name: code for code, name in enumerate(BLEND_TYPES)}


def compute_delta(t: float, duration: float, blend: str) -> float:
    """``CLerpInterval::compute_delta``: the lerp fraction at time ``t`` (duration 0 gives 1.0).

    noBlend t; easeIn (3t^2 - t^3)/2; easeOut (3t - t^3)/2; easeInOut 3t^2 - 2t^3, with
    t = clamp(t/duration, 0, 1).
    """
    code = _BLEND_CODES.get(blend)
    if code is None:
        raise ValueError(f"Invalid `blend`. Expected one of {', '.join(BLEND_TYPES)}. Received: blend={blend!r}")
    return _delta(t, duration, code)


def _delta(t: float, duration: float, code: int) -> float:
    if duration == 0.0:
        return 1.0
    t = min(max(t / duration, 0.0), 1.0)
    if code == _EASE_IN:
        t2 = t * t
        return (3.0 * t2 - t2 * t) * 0.5
    if code == _EASE_OUT:
        t2 = t * t
        return (3.0 * t - t2 * t) * 0.5
    if code == _EASE_IN_OUT:
        t2 = t * t
        return 3.0 * t2 - 2.0 * t * t2
    return t


def lerp_value(d: float, start: float, end: float) -> float:
    """``lerp_value``: start + d*(end - start)."""
    return start + d * (end - start)


def lerp_vec3(d: float, start: Vec3, end: Vec3) -> Vec3:
    """Component-wise :func:`lerp_value` (HPR included: degrees, no wrap, 0 -> 350 passes 175)."""
    return (
        start[0] + d * (end[0] - start[0]),
        start[1] + d * (end[1] - start[1]),
        start[2] + d * (end[2] - start[2]),
    )


class WaitLeaf(Node):
    """``WaitInterval``: time only (a meta interval does not even give it events)."""


class LerpLeaf(Node):
    """``CLerpNodePathInterval`` with bakeInStart=1, fluid=0 and no ``other`` node.

    A start value not given is read from the body by the first ``priv_step`` (inside
    ``priv_initialize`` or ``priv_instant``) and kept for good: replays, loops and rewinds reuse it.
    (``_prev_d`` only matters to bakeInStart=0 lerps, which the scenario language does not offer.)
    """

    def __init__(self, host: IntervalHost, spec: LerpSpec) -> None:
        super().__init__(spec.duration)
        self.host = host
        self.spec = spec
        self._blend = _BLEND_CODES[spec.blend]
        self.start_pos: Vec3 | None = spec.start_pos
        self.start_hpr: Vec3 | None = spec.start_hpr
        self.start_scale: float | None = spec.start_scale

    def priv_instant(self, at: float) -> None:
        # CLerpNodePathInterval::priv_instant does not call interval_done(): no done event.
        self.state = State.STARTED
        self.priv_step(self.duration, at)
        self.state = State.FINAL

    def priv_step(self, t: float, at: float) -> None:
        self.state = State.STARTED
        d = _delta(t, self.duration, self._blend)
        spec, host = self.spec, self.host
        # Read every start value first (one get_transform() in Panda3D), then write.
        pos: Vec3 | None = None
        hpr: Vec3 | None = None
        scale: float | None = None
        if spec.pos is not None:
            if self.start_pos is None:
                self.start_pos = host.get_pos(spec.body)
            pos = lerp_vec3(d, self.start_pos, spec.pos)
        if spec.hpr is not None:
            if self.start_hpr is None:
                self.start_hpr = host.get_hpr(spec.body)
            hpr = lerp_vec3(d, self.start_hpr, spec.hpr)
        if spec.scale is not None:
            if self.start_scale is None:
                self.start_scale = host.get_scale(spec.body)
            scale = lerp_value(d, self.start_scale, spec.scale)
        if pos is not None:
            host.set_pos(spec.body, pos)
        if hpr is not None:
            host.set_hpr(spec.body, hpr)
        if scale is not None:
            host.set_scale(spec.body, scale)
        self.curr_t = t
