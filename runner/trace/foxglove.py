"""Foxglove's well-known messages for the trace, built with Foxglove's precompiled protobuf classes
(``foxglove-schemas-protobuf``): the scene (``foxglove.SceneUpdate``), the log (``foxglove.Log``), the
sounds as audio (``foxglove.RawAudio``), and the per-step transforms (``foxglove.FrameTransforms``, through
a :class:`runner.trace.slots.StampedTemplate`).

Foxglove recognises these by their exact schema names, and so do Rerun's Foxglove lenses. Geometry is
published once, frame-locked to each body's frame; bodies move through /tf only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import fields, is_dataclass
from typing import Any

import numpy as np
from foxglove_schemas_protobuf.Color_pb2 import Color
from foxglove_schemas_protobuf.CubePrimitive_pb2 import CubePrimitive
from foxglove_schemas_protobuf.CylinderPrimitive_pb2 import CylinderPrimitive
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms
from foxglove_schemas_protobuf.KeyValuePair_pb2 import KeyValuePair
from foxglove_schemas_protobuf.LinePrimitive_pb2 import LinePrimitive
from foxglove_schemas_protobuf.Log_pb2 import Log
from foxglove_schemas_protobuf.Point3_pb2 import Point3
from foxglove_schemas_protobuf.Pose_pb2 import Pose
from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
from foxglove_schemas_protobuf.RawAudio_pb2 import RawAudio
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.SpherePrimitive_pb2 import SpherePrimitive
from foxglove_schemas_protobuf.TriangleListPrimitive_pb2 import TriangleListPrimitive
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from google.protobuf.timestamp_pb2 import Timestamp

from backends.geometry import quat_rotate
from backends.types import BodySpec, PlacedShape, ShapeKind
from reports.trace_format import BODY_ROW, WORLD_FRAME
from runner.trace.slots import StampedTemplate

__all__ = [
    "ENTITY_ARRAYS",
    "body_primitives",
    "body_spec_record",
    "FrameTransforms",
    "Log",
    "RawAudio",
    "SceneUpdate",
    "entity",
    "log",
    "raw_audio",
    "shape_primitives",
    "solid_primitives",
    "stamp",
    "transforms_template",
]

ENTITY_ARRAYS = ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models")

PLANE_EXTENT = 40.0  # metres: a plane is shown as a large thin cube whose top face is the plane
PLANE_THICKNESS = 0.01
SOLID_RGBA = (1.0, 0.8, 0.1, 0.3)  # collision solids: translucent amber
SOLID_OUTLINE_RGBA = (1.0, 0.8, 0.1, 0.9)


def stamp(ns: int) -> Timestamp:
    sec, nsec = divmod(int(ns), 1_000_000_000)
    return Timestamp(seconds=sec, nanos=nsec)


def _pose(position: Sequence[float] = (0.0, 0.0, 0.0)) -> Pose:
    """A pose at ``position`` with the identity orientation."""
    x, y, z = (float(c) for c in position)
    return Pose(position=Vector3(x=x, y=y, z=z), orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))


def _color(rgba: Sequence[float]) -> Color:
    return Color(r=float(rgba[0]), g=float(rgba[1]), b=float(rgba[2]), a=float(rgba[3]))


def _vec(v: Sequence[float]) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _point(v: Sequence[float]) -> Point3:
    return Point3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def cube(size: Sequence[float], rgba: Sequence[float], center: Sequence[float] = (0, 0, 0)) -> CubePrimitive:
    return CubePrimitive(pose=_pose(center), size=_vec(size), color=_color(rgba))


def sphere(radius: float, rgba: Sequence[float], center: Sequence[float] = (0, 0, 0)) -> SpherePrimitive:
    d = 2.0 * radius
    return SpherePrimitive(pose=_pose(center), size=_vec((d, d, d)), color=_color(rgba))


def cylinder(radius: float, length: float, rgba: Sequence[float]) -> CylinderPrimitive:
    """A cylinder along the local z axis, as the engine-neutral shapes define it."""
    d = 2.0 * radius
    return CylinderPrimitive(pose=_pose(), size=_vec((d, d, length)), bottom_scale=1.0, top_scale=1.0,
                             color=_color(rgba))  # fmt: skip


def _add_points(field: Any, points: Sequence[Sequence[float]]) -> None:
    """``points`` appended to a repeated Point3 field in place (``add``: half the time of building each Point3
    and copying it in; a robot's hulls are tens of thousands of points)."""
    add = field.add
    for p in points:
        add(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def triangles(points: Sequence[Sequence[float]], rgba: Sequence[float]) -> TriangleListPrimitive:
    prim = TriangleListPrimitive(pose=_pose(), color=_color(rgba))
    _add_points(prim.points, points)
    return prim


def line_loop(points: Sequence[Sequence[float]], rgba: Sequence[float], thickness: float = 2.0) -> LinePrimitive:
    """A closed outline, ``thickness`` in pixels."""
    prim = LinePrimitive(type=LinePrimitive.LINE_LOOP, pose=_pose(), thickness=thickness, scale_invariant=True,
                         color=_color(rgba))  # fmt: skip
    _add_points(prim.points, points)
    return prim


def entity(ns: int, frame_id: str, entity_id: str, metadata: Mapping[str, str] | None = None,
           **primitives: Sequence[Any]) -> SceneEntity:  # fmt: skip
    """A frame-locked, never-expiring SceneEntity; ``primitives`` by array name (cubes=[...], ...)."""
    unknown = set(primitives) - set(ENTITY_ARRAYS)
    if unknown:
        raise ValueError(f"unknown SceneEntity arrays {sorted(unknown)}; expected some of {ENTITY_ARRAYS}")
    out = SceneEntity(timestamp=stamp(ns), frame_id=frame_id, id=entity_id, frame_locked=True,
                      metadata=[KeyValuePair(key=k, value=v) for k, v in (metadata or {}).items()])  # fmt: skip
    out.lifetime.SetInParent()  # zero: never expires
    for name, prims in primitives.items():
        getattr(out, name).extend(prims)
    return out


def shape_primitives(
    kind: str, size: Sequence[float], radius: float, length: float, rgba: Sequence[float], scale: float = 1.0
) -> dict[str, list[Any]]:
    """Primitives (by SceneEntity array name) of a body shape in its own frame, as backends.types defines it."""
    r, half = radius * scale, length * scale / 2.0
    if kind == "box":
        return {"cubes": [cube([c * scale for c in size], rgba)]}
    if kind == "sphere":
        return {"spheres": [sphere(r, rgba)]}
    if kind == "cylinder":
        return {"cylinders": [cylinder(r, 2.0 * half, rgba)]}
    if kind == "capsule":
        caps = [sphere(r, rgba, (0.0, 0.0, half)), sphere(r, rgba, (0.0, 0.0, -half))]
        return {"cylinders": [cylinder(r, 2.0 * half, rgba)], "spheres": caps}
    if kind == "plane":  # normal = local +z, through the body's origin
        slab = (PLANE_EXTENT, PLANE_EXTENT, PLANE_THICKNESS)
        return {"cubes": [cube(slab, rgba, (0.0, 0.0, -PLANE_THICKNESS / 2.0))]}
    raise ValueError(f"unknown shape {kind!r}")


def mesh_points(placed: PlacedShape, scale: float = 1.0) -> list[tuple[float, float, float]]:
    """A mesh shape's triangles as a flat list of points (three per triangle), in the shape's frame."""
    mesh = placed.shape.mesh
    if mesh is None:
        return []
    v = mesh.vertices
    if scale == 1.0:  # the vertices themselves (c * 1.0 is c)
        return [v[i] for face in mesh.faces for i in face]
    return [(x * scale, y * scale, z * scale) for face in mesh.faces for x, y, z in (v[i] for i in face)]


def _placed(prim: Any, pos: Sequence[float], quat: Sequence[float]) -> Any:
    """``prim`` (posed in its shape's frame, identity orientation) moved to the shape's pose in the body frame."""
    p = prim.pose.position
    x, y, z = quat_rotate((quat[0], quat[1], quat[2], quat[3]), (p.x, p.y, p.z))
    prim.pose.position.x, prim.pose.position.y, prim.pose.position.z = x + pos[0], y + pos[1], z + pos[2]
    prim.pose.orientation.w, prim.pose.orientation.x = float(quat[0]), float(quat[1])
    prim.pose.orientation.y, prim.pose.orientation.z = float(quat[2]), float(quat[3])
    return prim


def body_primitives(body: BodySpec, scale: float = 1.0) -> dict[str, list[Any]]:
    """Primitives of every shape of ``body`` in the body frame: one shape at the origin for a primitive body;
    each shape of a compound body at its local pose (meshes as triangle lists: the hull the engines collide
    with, or the static triangle mesh)."""
    if body.shape.kind is not ShapeKind.COMPOUND:
        sh = body.shape
        return shape_primitives(sh.kind.value, sh.size, sh.radius, sh.length, body.color, scale)
    out: dict[str, list[Any]] = {}
    for placed in body.shapes:
        sh, rgba = placed.shape, placed.color or body.color
        if sh.kind in (ShapeKind.CONVEX, ShapeKind.TRIMESH):
            prims: dict[str, list[Any]] = {"triangles": [triangles(mesh_points(placed, scale), rgba)]}
        else:
            prims = shape_primitives(sh.kind.value, sh.size, sh.radius, sh.length, rgba, scale)
        pos = tuple(c * scale for c in placed.pos)
        for name, items in prims.items():
            out.setdefault(name, []).extend(_placed(p, pos, placed.quat) for p in items)
    return out


def _fields(value: Any) -> Any:
    """``dataclasses.asdict``'s dicts without its copies: a dataclass becomes a dict of its fields, a tuple of
    dataclasses a tuple of dicts, and anything else (numbers, enums, and the specs' tuples of numbers: a
    mesh's vertices and faces, thousands on a robot's links) is kept as it is, being immutable: the same JSON,
    at a fraction of the time (asdict deep-copied every vertex: 40 ms for the KUKA arm's hulls)."""
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: _fields(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, tuple) and value and is_dataclass(value[0]):  # the specs' tuples are of one kind
        return tuple(_fields(v) for v in value)
    return value


def body_spec_record(body: BodySpec) -> dict[str, Any]:
    """A body's spec for the trace metadata: the fields of a primitive body exactly as before robots (so their
    traces stay byte-identical); a compound body adds its shapes, meshes, COM and principal axes."""
    record = {f.name: _fields(getattr(body, f.name)) for f in fields(body) if f.name != "visuals"}
    # the visuals are drawn on /scene; the metadata keeps what the engines simulate
    if body.shape.kind is not ShapeKind.COMPOUND:
        for key in ("shapes", "com", "inertia_quat"):
            record.pop(key)
        record["shape"].pop("mesh")
    return record


def solid_primitives(
    kind: str, center: Sequence[float], radius: float, size: Sequence[float], vertices: Sequence[Sequence[float]]
) -> dict[str, list[Any]]:
    """Translucent primitives of a collision solid; a polygon gets both faces and an outline."""
    if kind == "sphere":
        return {"spheres": [sphere(radius, SOLID_RGBA, center)]}
    if kind == "box":
        return {"cubes": [cube(size, SOLID_RGBA, center)]}
    if kind == "polygon":
        v = vertices
        front = [p for i in range(1, len(v) - 1) for p in (v[0], v[i], v[i + 1])]
        back = [p for i in range(1, len(v) - 1) for p in (v[0], v[i + 1], v[i])]
        return {"triangles": [triangles(front + back, SOLID_RGBA)], "lines": [line_loop(v, SOLID_OUTLINE_RGBA)]}
    raise ValueError(f"unknown solid kind {kind!r}; expected sphere, polygon or box")


def log(ns: int, level: int, message: str, name: str) -> Log:
    return Log(timestamp=stamp(ns), level=level, message=message, name=name)  # type: ignore[arg-type]


def raw_audio(ns: int, pcm: np.ndarray, sample_rate: int) -> RawAudio:
    """``pcm``: (frames, channels) int16 samples, written little-endian and interleaved (``pcm-s16``)."""
    frames = np.ascontiguousarray(pcm, dtype="<i2")
    return RawAudio(timestamp=stamp(ns), data=frames.tobytes(), format="pcm-s16", sample_rate=int(sample_rate),
                    number_of_channels=int(frames.shape[1]))  # fmt: skip


def transforms_template(bodies: Sequence[str]) -> StampedTemplate:
    """/tf for ``bodies``, every body a frame parented to ``world``, values from the step's (N, 13) body rows
    (:data:`reports.trace_format.BODY_ROW`: pos x y z, quat w x y z, then velocities)."""
    width = len(BODY_ROW)
    px, py, pz = (BODY_ROW.index(f"pos.{c}") for c in "xyz")
    qw, qx, qy, qz = (BODY_ROW.index(f"quat.{c}") for c in "wxyz")

    def fill(values: np.ndarray, when: Timestamp) -> FrameTransforms:
        msg = FrameTransforms()
        for name, row in zip(bodies, values.reshape(-1, width).tolist(), strict=True):
            t = msg.transforms.add(parent_frame_id=WORLD_FRAME, child_frame_id=name)
            t.timestamp.CopyFrom(when)
            t.translation.x, t.translation.y, t.translation.z = row[px], row[py], row[pz]
            t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w = row[qx], row[qy], row[qz], row[qw]
        return msg

    return StampedTemplate(fill, width * len(bodies), len(bodies))
