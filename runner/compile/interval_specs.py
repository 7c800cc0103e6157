"""What the runner's compiler builds from a scenario's ``intervals:`` section, and what it implements.

The specs are frozen, engine-neutral descriptions of Panda3D intervals (``direct.interval``): a
``LerpSpec`` is one LerpPos/Hpr/PosHpr/Scale/PosHprScaleInterval of one body, ``WaitSpec`` a
``Wait``, ``FuncSpec`` a ``Func`` (an action step), ``SoundSpec`` a ``SoundInterval``, and
``SequenceSpec``/``ParallelSpec`` the meta intervals. The step loop plays them
(:mod:`runner.sim.intervals`).

Every spec is one Panda3D *object*: a spec used in two places (two interval ids, or twice in one
Sequence) is built as two independent objects, each with its own play state and baked start values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final

__all__ = [
    "BLEND_TYPES",
    "FuncSpec",
    "IntervalSpec",
    "LerpSpec",
    "ParallelSpec",
    "SequenceSpec",
    "SoundSpec",
    "Vec3",
    "WaitSpec",
]

Vec3 = tuple[float, float, float]

#: ``CLerpInterval::string_blend_type``: every other string is BT_invalid in Panda3D.
BLEND_TYPES: Final = ("noBlend", "easeIn", "easeOut", "easeInOut")


def _check_duration(kind: str, value: float | None, field: str = "duration") -> None:
    if value is not None and not (math.isfinite(value) and value >= 0.0):
        raise ValueError(f"Invalid `{kind}.{field}`. Expected a finite number >= 0. Received: {field}={value!r}")


@dataclass(frozen=True)
class LerpSpec:
    """A LerpPos/Hpr/PosHpr/Scale/PosHprScaleInterval of one body (bakeInStart=1, fluid=0, no `other`)."""

    body: str
    duration: float
    blend: str = "noBlend"  # noBlend | easeIn | easeOut | easeInOut
    pos: Vec3 | None = None  # end values; None = this property is not lerped
    hpr: Vec3 | None = None  # degrees, per component, no wrap
    scale: float | None = None  # uniform
    start_pos: Vec3 | None = None  # None = captured at the first step (bakeInStart=1)
    start_hpr: Vec3 | None = None
    start_scale: float | None = None

    def __post_init__(self) -> None:
        _check_duration("LerpSpec", self.duration)
        if self.blend not in BLEND_TYPES:
            raise ValueError(
                f"Invalid `LerpSpec.blend`. Expected one of {', '.join(BLEND_TYPES)}. Received: blend={self.blend!r}"
            )
        if self.pos is None and self.hpr is None and self.scale is None:
            raise ValueError(f"Invalid `LerpSpec` of body {self.body!r}. Expected at least one of pos, hpr, scale.")
        for name in ("pos", "hpr", "scale"):
            if getattr(self, name) is None and getattr(self, "start_" + name) is not None:
                raise ValueError(f"Invalid `LerpSpec.start_{name}`: given without `{name}` (body {self.body!r}).")


@dataclass(frozen=True)
class WaitSpec:
    """``Wait(d)``: time only; a child of a meta interval gets no events at all."""

    duration: float

    def __post_init__(self) -> None:
        _check_duration("WaitSpec", self.duration)


@dataclass(frozen=True)
class FuncSpec:
    """``Func``: an action step of duration 0, open-ended (run even when skipped by a finish)."""

    actions: Any  # opaque: passed back to host.run_actions
    label: str = "func"


@dataclass(frozen=True)
class SoundSpec:
    """``SoundInterval(sound, loop, duration, name, volume, startTime)``."""

    sound: str
    duration: float  # already resolved by the compiler (sound length - start_time, or given)
    volume: float = 1.0
    loop: bool = False
    start_time: float = 0.0
    #: the sound file's length (``sound.length()``): a (re)start at offset >= length plays nothing.
    #: None = unknown, taken as ``start_time + duration`` (the default duration's case).
    length: float | None = None

    def __post_init__(self) -> None:
        _check_duration("SoundSpec", self.duration)
        _check_duration("SoundSpec", self.start_time, "start_time")
        _check_duration("SoundSpec", self.length, "length")

    @property
    def sound_length(self) -> float:
        return self.start_time + self.duration if self.length is None else self.length


@dataclass(frozen=True)
class SequenceSpec:
    """``Sequence(*children, duration=None)``: each child starts at the previous one's end."""

    children: tuple[IntervalSpec, ...]
    duration: float | None = None  # Panda3D's "phony" duration for the level

    def __post_init__(self) -> None:
        _check_duration("SequenceSpec", self.duration)


@dataclass(frozen=True)
class ParallelSpec:
    """``Parallel(*children, duration=None)``: every child starts at the level's start."""

    children: tuple[IntervalSpec, ...]
    duration: float | None = None

    def __post_init__(self) -> None:
        _check_duration("ParallelSpec", self.duration)


IntervalSpec = LerpSpec | WaitSpec | FuncSpec | SoundSpec | SequenceSpec | ParallelSpec
