"""Reading a built world back (``Backend.imported_model``): the conversions every adapter shares.

Each adapter reads its engine's own numbers (mass, inertia tensor or principal moments, the COM's world
position, joint axes, stops, damping); these turn them into ``backends.types.ImportedBody``/``ImportedJoint``
the same way for every engine, so that a difference between engines is the engines', not the adapters'.
Nothing here imports an engine.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..geometry import quat_conj, quat_rotate
from ..types import BodySpec, ImportedBody, Vec3

#: a stop at or beyond this magnitude is no stop (adapters hand engines that cannot take inf +-1e30)
NO_STOP = 1e29


def principal(tensor: Sequence[Sequence[float]] | np.ndarray) -> Vec3:
    """The principal moments of a symmetric 3x3 inertia tensor, ascending (its axes are not compared: an
    engine may keep them as it likes)."""
    t = np.asarray(tensor, dtype=np.float64).reshape(3, 3)
    w = np.linalg.eigvalsh((t + t.T) / 2.0)
    return (float(w[0]), float(w[1]), float(w[2]))


def ascending(moments: Sequence[float]) -> Vec3:
    """Principal moments an engine keeps as a diagonal, ascending."""
    a, b, c = sorted(float(m) for m in moments)
    return (a, b, c)


def com_in_body(spec: BodySpec, com_world: Sequence[float]) -> Vec3:
    """The engine's COM (world frame, before any step) in the body frame as the world placed it."""
    d = (float(com_world[0]) - spec.pos[0], float(com_world[1]) - spec.pos[1], float(com_world[2]) - spec.pos[2])
    x, y, z = quat_rotate(quat_conj(spec.quat), d)
    return (float(x), float(y), float(z))


def body(spec: BodySpec, mass: float, inertia: Vec3, com_world: Sequence[float], shapes: int) -> ImportedBody:
    return ImportedBody(spec.name, float(mass), inertia, com_in_body(spec, com_world), int(shapes))


def stops(
    lo: float | None, hi: float | None, sign: float = 1.0, start: float = 0.0
) -> tuple[float | None, float | None]:
    """An engine's stops in the world joint's coordinate: ``world = sign * engine - start`` (a side beyond
    :data:`NO_STOP`, or not finite, is no stop)."""

    def side(v: float | None) -> float | None:
        return None if v is None or not math.isfinite(v) or abs(v) >= NO_STOP else float(v)

    a, b = side(lo), side(hi)
    if sign < 0:
        a, b = (None if b is None else -b), (None if a is None else -a)
    return (None if a is None else a - start), (None if b is None else b - start)


def unit(axis: Sequence[float], sign: float = 1.0) -> Vec3:
    """An engine's axis (world frame) in the world joint's sense, as the engine holds it (not renormalised:
    a float32 engine's rounding stays visible)."""
    return (sign * float(axis[0]), sign * float(axis[1]), sign * float(axis[2]))


def finite_or_none(value: float) -> float | None:
    """A limit an engine keeps as a number, None where it keeps none (inf)."""
    v = float(value)
    return v if math.isfinite(v) and abs(v) < NO_STOP else None
