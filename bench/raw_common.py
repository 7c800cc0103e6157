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
