"""How tall a stack of bodies a world starts with (issue 17: settings a backend picks for a pile).

Iterative and soft contact solvers lose accuracy with the number of contacts a load passes through: the
bottom contact of a column of H bodies carries H weights, and the column's overturning moment about it
grows as H^2 (H weights times a lever of H/2 body heights). Backends size their solver from :func:`stack_height`:
the longest chain of dynamic bodies, each above the previous one along gravity with overlapping
footprints, so that it will rest on it (docs/backends/*.md, "Stacking"). A column dropped with gaps counts
as stacked. :func:`refuse_column` is the one refusal of a column taller than an engine holds. Nothing here
imports an engine.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..errors import UnsupportedFeature
from ..geometry import quat_matrices
from ..types import BodySpec, CompiledWorld, Motion, Shape, ShapeKind

#: Below this many metres of overlap, two footprints only touch (a grid of boxes side by side does not stack).
_OVERLAP = 1e-9


def _extent(shape: Shape, rot: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) offsets of ``shape`` (turned by ``rot``) along each of the three ``axes`` (rows)."""
    local = axes @ rot  # each axis in the shape's frame
    kind = shape.kind
    if kind is ShapeKind.BOX:
        half = np.abs(local) @ (0.5 * np.asarray(shape.size, dtype=np.float64))
        return -half, half
    if kind is ShapeKind.SPHERE:
        r = np.full(3, shape.radius)
        return -r, r
    if kind in (ShapeKind.CAPSULE, ShapeKind.CYLINDER):
        along = np.abs(local[:, 2]) * 0.5 * shape.length
        if kind is ShapeKind.CAPSULE:
            half = along + shape.radius
        else:
            half = along + shape.radius * np.sqrt(np.clip(1.0 - local[:, 2] ** 2, 0.0, 1.0))
        return -half, half
    if shape.mesh is not None and shape.mesh.vertices:
        proj = np.asarray(shape.mesh.vertices, dtype=np.float64) @ local.T
        return proj.min(axis=0), proj.max(axis=0)
    return np.zeros(3), np.zeros(3)  # a plane or an empty shape: nothing to stand on


def _bounds(body: BodySpec, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The body's bounding box along ``axes`` (rows: two horizontal, then up) at its start pose."""
    rot = quat_matrices(body.quat)
    origin = axes @ np.asarray(body.pos, dtype=np.float64)
    lows, highs = [], []
    for placed in body.placed_shapes():
        centre = origin + axes @ (rot @ np.asarray(placed.pos, dtype=np.float64))
        lo, hi = _extent(placed.shape, rot @ quat_matrices(placed.quat), axes)
        lows.append(centre + lo)
        highs.append(centre + hi)
    if not lows:
        return origin, origin
    return np.min(lows, axis=0), np.max(highs, axis=0)


def _axes(gravity: tuple[float, float, float]) -> np.ndarray:
    """Two horizontal unit vectors and the up vector (-gravity; +z without gravity)."""
    g = np.asarray(gravity, dtype=np.float64)
    n = float(np.linalg.norm(g))
    up = -g / n if n > 0.0 else np.array([0.0, 0.0, 1.0])
    side = np.array([1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = side - up * float(side @ up)
    e1 /= np.linalg.norm(e1)
    return np.array([e1, np.cross(up, e1), up])


#: A body whose bottom starts more than this above the top of the one under it is dropped onto it (it lands
#: at sqrt(2 g 1 mm) = 0.14 m/s or faster); closer, it starts resting on it (conformance 12: 1e-5 m deep).
LANDING_GAP = 1e-3


@dataclass(frozen=True)
class Stacks:
    """The tallest starting column, and the tallest one in which some body is dropped onto the one below."""

    tallest: int
    landing: int


def stacks(world: CompiledWorld) -> Stacks:
    """How tall the world's starting columns are (0 without dynamic bodies).

    Body B stands on body A when B's lowest point is above A's centre (along -gravity) and their footprints
    (bounding boxes across gravity) overlap; a column is a chain of such bodies, and a landing column one
    in which some body starts more than :data:`LANDING_GAP` above the highest body under it. O(n^2) in the
    number of dynamic bodies, vectorised (10,000 bodies: well under a second).
    """
    axes = _axes(world.gravity)
    dynamic = [b for b in world.bodies if b.motion is Motion.DYNAMIC]
    if not dynamic:
        return Stacks(0, 0)
    bounds = [_bounds(b, axes) for b in dynamic]
    lo = np.array([b[0] for b in bounds])
    hi = np.array([b[1] for b in bounds])
    centre = 0.5 * (lo[:, 2] + hi[:, 2])
    order = np.argsort(lo[:, 2], kind="stable")
    lo, hi, centre = lo[order], hi[order], centre[order]
    height = np.ones(len(dynamic), dtype=np.int64)
    landing = np.zeros(len(dynamic), dtype=np.int64)  # 0: no chain ending here has a dropped link
    for k in range(1, len(dynamic)):
        below = (
            (centre[:k] < lo[k, 2])
            & (np.minimum(hi[:k, 0], hi[k, 0]) - np.maximum(lo[:k, 0], lo[k, 0]) > _OVERLAP)
            & (np.minimum(hi[:k, 1], hi[k, 1]) - np.maximum(lo[:k, 1], lo[k, 1]) > _OVERLAP)
        )
        if not below.any():
            continue
        height[k] = 1 + int(height[:k][below].max())
        if lo[k, 2] - float(hi[:k, 2][below].max()) > LANDING_GAP:  # dropped onto the highest body below
            landing[k] = height[k]
        else:
            best = int(landing[:k][below].max())
            landing[k] = 1 + best if best else 0
    return Stacks(int(height.max()), int(landing.max()))


def stack_height(world: CompiledWorld) -> int:
    """The number of dynamic bodies in the tallest column the world starts with (see :func:`stacks`)."""
    return stacks(world).tallest


def free_bodies(world: CompiledWorld) -> CompiledWorld:
    """The world without the bodies a joint holds, for a stacking limit: a robot's links are carried by their
    joints, not by contacts with the link below (a franka panda's 8 links start one above the other)."""
    held = {name for j in world.joints for name in (j.body, j.other) if name is not None}
    return dataclasses.replace(world, bodies=tuple(b for b in world.bodies if b.name not in held), joints=())


__all__ = ["LANDING_GAP", "Stacks", "free_bodies", "stack_height", "stacks"]


def refuse_column(
    backend: str, height: int, limit: int, *, holds: str, why: str, column: str = "a column", detail: str = ""
) -> None:
    """The engines' stacking limit, one refusal for all (UnsupportedFeature, before anything is built): a world
    starting with ``column`` of ``height`` bodies (``detail``: how they stand) when the engine holds at most
    ``limit``. ``holds`` names the engine and its verb ("MuJoCo holds"), ``why`` the measured cause and what
    to use instead."""
    if height > limit:
        raise UnsupportedFeature(
            f"{backend}: the world starts with {column} of {height} bodies{detail}; {holds} at most {limit}: {why}"
        )
