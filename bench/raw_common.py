"""What every hand-written loop shares: the world it may build, and how a loop is timed."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from backends.types import CompiledWorld, Motion, ShapeKind


class RawLoop(Protocol):
    """One engine driven directly: built from a world and the adapter's settings, stepped, read."""

    def step(self) -> None: ...

    def read(self) -> np.ndarray:
        """(N, 13) rows: pos, quat (w x y z), linear and angular velocity, in world.bodies order."""
        ...

    def close(self) -> None: ...


@dataclass(frozen=True)
class RawTiming:
    seconds: float  # build + steps (+ per-step reads when asked)
    build_seconds: float
    final: np.ndarray  # (N, 13) after the last step


def check_pile(world: CompiledWorld) -> None:
    """The loops build what the benchmark world holds: dynamic boxes, one static plane, one surface."""
    kinds = {(b.motion, b.shape.kind) for b in world.bodies}
    if not kinds <= {(Motion.DYNAMIC, ShapeKind.BOX), (Motion.STATIC, ShapeKind.PLANE)}:
        raise ValueError(f"a hand-written loop builds boxes and a plane only, not {sorted(map(str, kinds))}")
    if world.joints or world.pair_surfaces or world.substeps != 1:
        raise ValueError("a hand-written loop builds no joints, pair surfaces or substeps")


def time_loop(make: Any, world: CompiledWorld, settings: Mapping[str, Any], steps: int, read: bool) -> RawTiming:
    """Build with ``make(world, settings)``, step ``steps`` times (reading every state if ``read``)."""
    check_pile(world)
    start = time.perf_counter()
    loop: RawLoop = make(world, settings)
    built = time.perf_counter()
    try:
        if read:
            for _ in range(steps):
                loop.step()
                loop.read()
        else:
            for _ in range(steps):
                loop.step()
        end = time.perf_counter()
        final = loop.read()
    finally:
        loop.close()
    return RawTiming(end - start, built - start, final)


@dataclass(frozen=True)
class Servo:
    """One position servo as a hand-written loop drives it: ``vel = gain (target - q)``, clamped to vmax."""

    joint: int  # world joint index
    gain: float
    fmax: float
    vmax: float | None
    #: the joint's start position (program.joint_zeros): an engine that reads the joint from its start (as
    #: PyBullet builds a robot at its start pose) adds it to read from the model's zero, as the runner does
    zero: float = 0.0


class RobotLoop(Protocol):
    """The adapter's own engine world (same bodies, joints and settings: the same physics), stepped and read
    by hand as the engine's users do: the servos' commands from the last joint reading, the engine's step,
    then every link's pose and velocity and every joint's position, velocity and motor force."""

    def step(self, targets: list[float]) -> None: ...

    def read(self) -> None: ...

    def joint_positions(self) -> dict[int, float]:
        """World joint index -> its position (the runner's coordinate) after the last read."""
        ...


def servo_rates(servos: list[Servo], targets: list[float], q: list[float]) -> list[float]:
    """Each servo's commanded rate (the runner's servo law, runner.sim.servo), in the engine's coordinate."""
    out = []
    for s, target, now in zip(servos, targets, q, strict=True):
        vel = s.gain * (target - now)
        out.append(vel if s.vmax is None else max(-s.vmax, min(s.vmax, vel)))
    return out
