"""The trace's scene: what each ``TraceWriter.scene`` call publishes, as ``foxglove.SceneEntity`` messages by topic.

* ``/scene``: every body as it is drawn (``body/<name>``): a model's visuals (URDF `<visual>`, MJCF's visible
  geoms: meshes as indexed triangle lists in their material colours) where it has them, else its collision
  shapes; a plane at its size when the model gives one (else :data:`PLANE_EXTENT`) with a grid on it; every
  joint (``joint/<name>``, at t = 0): its axis as an arrow through its anchor (hinge, universal: both axes),
  along its direction from the body's origin (slider), a ball at the anchor (ball, hinge);
  the collision solids (``solid/<body>/<node>``, translucent).
* ``/scene/collision``: the collision shapes of every body drawn by its visuals that has any
  (``collision/<name>``, translucent amber), so a user can turn them on; the layout keeps that topic hidden.

Entities are frame-locked to their body's frame (bodies move through /tf only) and never expire; a later
call replaces them by id. Built by the trace writer and by the live viewer's tap (runner.view.tap), so
the window draws what the trace records.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from foxglove_schemas_protobuf.ArrowPrimitive_pb2 import ArrowPrimitive
from foxglove_schemas_protobuf.LinePrimitive_pb2 import LinePrimitive

from backends.geometry import quat_conj, quat_rotate
from backends.types import BodySpec, JointKind, JointSpec, PlacedShape, Shape, ShapeKind, Vec3
from reports import trace_format as tf
from runner.trace import foxglove as fx

__all__ = ["COLLISION_RGBA", "PLANE_EXTENT", "SolidVisual", "joint_entities", "scene_entities"]

PLANE_EXTENT = fx.PLANE_EXTENT  # metres: an unbounded plane is drawn this wide
COLLISION_RGBA = fx.SOLID_RGBA
GRID_RGBA = (0.25, 0.25, 0.25, 0.6)
GRID_LIFT = 5e-4  # metres above the plane, so the lines are not hidden in its top face
JOINT_RGBA = {"hinge": (0.85, 0.15, 0.85, 1.0), "slider": (0.1, 0.75, 0.85, 1.0),
              "universal": (0.85, 0.15, 0.85, 1.0), "ball": (0.85, 0.15, 0.85, 1.0)}  # fmt: skip
ARROW_MIN, ARROW_MAX = 0.05, 0.5  # metres: a joint's arrow is 0.6 x its body's size, within these


@dataclass(frozen=True)
class SolidVisual:
    """A Panda3D-style collision solid for the 3D view (translucent), in its body's frame."""

    node: str
    body: str
    kind: str  # "sphere" | "polygon" | "box"
    center: Vec3 = (0.0, 0.0, 0.0)
    radius: float = 0.0
    size: Vec3 = (0.0, 0.0, 0.0)  # box: full edge lengths
    vertices: tuple[Vec3, ...] = ()  # polygon: body frame, already scaled; order gives the normal


def grid_spacing(extent: float) -> float:
    """Grid lines 1 m apart on a plane 4 m wide or more; on a smaller one, about a tenth of it (1, 2, 5 x 10^n)."""
    if extent >= 4.0:
        return 1.0
    raw = max(extent, 1e-6) / 10.0
    power = 10.0 ** math.floor(math.log10(raw))
    return next(k * power for k in (1.0, 2.0, 5.0, 10.0) if k * power >= raw - 1e-12)


def _grid(size_x: float, size_y: float) -> LinePrimitive:
    """Lines of a grid on the plane's top face (local z = 0), centred on its origin, as a LINE_LIST."""
    step = grid_spacing(min(size_x, size_y))
    points: list[tuple[float, float, float]] = []
    hx, hy = size_x / 2.0, size_y / 2.0
    for k in range(-int(hx / step + 1e-9), int(hx / step + 1e-9) + 1):
        points += [(k * step, -hy, GRID_LIFT), (k * step, hy, GRID_LIFT)]
    for k in range(-int(hy / step + 1e-9), int(hy / step + 1e-9) + 1):
        points += [(-hx, k * step, GRID_LIFT), (hx, k * step, GRID_LIFT)]
    return LinePrimitive(type=LinePrimitive.LINE_LIST, pose=fx._pose(), thickness=1.0, scale_invariant=True,
                         points=[fx._point(p) for p in points], color=fx._color(GRID_RGBA))  # fmt: skip


def plane_primitives(shape: Shape, rgba: Sequence[float], scale: float = 1.0) -> dict[str, list[Any]]:
    """A plane (normal local +z through the origin) as a thin slab whose top face is the plane, at its size
    when it has one (an MJCF plane's), and a grid on it."""
    sx, sy = (shape.size[0] * scale, shape.size[1] * scale) if shape.size[0] > 0 and shape.size[1] > 0 else (
        PLANE_EXTENT, PLANE_EXTENT)  # fmt: skip
    slab = fx.cube((sx, sy, fx.PLANE_THICKNESS), rgba, (0.0, 0.0, -fx.PLANE_THICKNESS / 2.0))
    return {"cubes": [slab], "lines": [_grid(sx, sy)]}


def _mesh_triangles(placed: PlacedShape, rgba: Sequence[float], scale: float) -> Any:
    """A mesh as an indexed triangle list (each vertex once)."""
    mesh = placed.shape.mesh
    vertices, faces = (mesh.vertices, mesh.faces) if mesh is not None else ((), ())
    prim = fx.triangles(vertices if scale == 1.0 else [(x * scale, y * scale, z * scale) for x, y, z in vertices], rgba)
    prim.indices.extend(i for face in faces for i in face)
    return prim


def _shape_prims(placed: PlacedShape, rgba: Sequence[float], scale: float, indexed: bool) -> dict[str, list[Any]]:
    sh = placed.shape
    if sh.kind in (ShapeKind.CONVEX, ShapeKind.TRIMESH):
        prim = _mesh_triangles(placed, rgba, scale) if indexed else fx.triangles(fx.mesh_points(placed, scale), rgba)
        return {"triangles": [prim]}
    if sh.kind is ShapeKind.PLANE:
        return plane_primitives(sh, rgba, scale)
    return fx.shape_primitives(sh.kind.value, sh.size, sh.radius, sh.length, rgba, scale)


def _placed_prims(shapes: Sequence[PlacedShape], rgba: Sequence[float], scale: float,
                  indexed: bool) -> dict[str, list[Any]]:  # fmt: skip
    out: dict[str, list[Any]] = {}
    for placed in shapes:
        prims = _shape_prims(placed, placed.color or rgba, scale, indexed)
        pos = tuple(c * scale for c in placed.pos)
        for name, items in prims.items():
            out.setdefault(name, []).extend(fx._placed(p, pos, placed.quat) for p in items)
    return out


def body_drawn(body: BodySpec, scale: float = 1.0) -> dict[str, list[Any]]:
    """The primitives of ``body`` as it is drawn: its visuals, else its collision shapes (planes with a grid)."""
    if body.visuals:
        return _placed_prims(body.visuals, body.color, scale, indexed=True)
    if body.shape.kind is ShapeKind.PLANE:
        return plane_primitives(body.shape, body.color, scale)
    return fx.body_primitives(body, scale)


def body_collision(body: BodySpec, scale: float = 1.0) -> dict[str, list[Any]]:
    """The collision shapes of ``body`` in one translucent colour."""
    plain = replace(body, color=COLLISION_RGBA, shapes=tuple(replace(p, color=None) for p in body.shapes))
    return fx.body_primitives(plain, scale)


def _extent(body: BodySpec) -> float:
    """A length for ``body``'s drawings: the largest distance of its collision shapes from its origin."""
    far = 0.0
    for placed in body.placed_shapes():
        s = placed.shape
        if s.kind is ShapeKind.PLANE:
            continue
        if s.mesh is not None and s.mesh.vertices:
            reach = float(np.linalg.norm(np.asarray(s.mesh.vertices, dtype=float), axis=1).max())
        else:
            reach = math.hypot(*(c / 2.0 for c in s.size)) if any(s.size) else math.hypot(s.radius, s.length / 2.0)
            reach = max(reach, s.radius + s.length / 2.0)
        far = max(far, math.hypot(*placed.pos) + reach)
    return far


def _x_to(axis: Sequence[float]) -> tuple[float, float, float, float]:
    """The rotation (w, x, y, z) taking +x onto the unit ``axis`` (an arrow's pose)."""
    a = np.asarray(axis, dtype=float)
    a = a / max(float(np.linalg.norm(a)), 1e-300)
    if a[0] < -1.0 + 1e-12:
        return (0.0, 0.0, 0.0, 1.0)  # half a turn about z
    w, v = 1.0 + a[0], np.cross((1.0, 0.0, 0.0), a)
    n = math.sqrt(w * w + float(v @ v))
    return (w / n, float(v[0]) / n, float(v[1]) / n, float(v[2]) / n)


def _arrow(base: Sequence[float], axis: Sequence[float], length: float, rgba: Sequence[float]) -> ArrowPrimitive:
    q = _x_to(axis)
    pose = fx._pose(base)
    pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z = q
    return ArrowPrimitive(pose=pose, shaft_length=0.75 * length, shaft_diameter=0.04 * length,
                          head_length=0.25 * length, head_diameter=0.1 * length, color=fx._color(rgba))  # fmt: skip


def joint_entities(ns: int, joints: Sequence[JointSpec], bodies: Mapping[str, BodySpec]) -> list[Any]:
    """A ``joint/<name>`` entity per hinge, slider, ball and universal joint, in its (child) body's frame as
    the body starts, from the joint's anchor and axes at the start (world frame)."""
    out = []
    for j in joints:
        body = bodies.get(j.body)
        if body is None or j.kind is JointKind.FIXED:
            continue
        back = quat_conj(body.quat)
        anchor = quat_rotate(back, tuple(a - p for a, p in zip(j.anchor, body.pos, strict=True)))
        length = min(max(0.6 * _extent(body), ARROW_MIN), ARROW_MAX)
        rgba = JOINT_RGBA.get(j.kind.value, JOINT_RGBA["hinge"])
        arrows, spheres = [], []
        axes = [j.axis] + ([j.axis2] if j.kind is JointKind.UNIVERSAL and j.axis2 is not None else [])
        for world_axis in axes if j.kind is not JointKind.BALL else []:
            axis = quat_rotate(back, world_axis)
            if j.kind is JointKind.SLIDER:
                arrows.append(_arrow((0.0, 0.0, 0.0), axis, length, rgba))
            else:
                base = tuple(a - 0.5 * length * d for a, d in zip(anchor, axis, strict=True))
                arrows.append(_arrow(base, axis, length, rgba))
        if j.kind is not JointKind.SLIDER:
            spheres.append(fx.sphere(0.06 * length, rgba, anchor))
        info = {"joint": j.name, "kind": j.kind.value}
        out.append(fx.entity(ns, j.body, f"joint/{j.name}", info, arrows=arrows, spheres=spheres))
    return out


def scene_entities(ns: int, bodies: Sequence[BodySpec], joints: Sequence[JointSpec] = (),
                   scales: Mapping[str, float] | None = None) -> dict[str, list[Any]]:  # fmt: skip
    """The bodies' and joints' entities by topic (module docstring); ``scales[name]`` multiplies a body's
    compiled shapes (default 1). Pass no joints on a later call: their entities stay."""
    scales = scales or {}
    drawn, collision = [], []
    for b in bodies:
        scale = scales.get(b.name, 1.0)
        info = {"shape": b.shape.kind.value, "motion": b.motion.value}
        drawn.append(fx.entity(ns, b.name, f"body/{b.name}", info, **body_drawn(b, scale)))
        if b.visuals and b.shapes:
            collision.append(fx.entity(ns, b.name, f"collision/{b.name}", info, **body_collision(b, scale)))
    drawn += joint_entities(ns, joints, {b.name: b for b in bodies})
    out = {tf.TOPIC_SCENE: drawn}
    if collision:
        out[tf.TOPIC_SCENE_COLLISION] = collision
    return out
