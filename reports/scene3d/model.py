"""What a run looks like, engine-neutral: the bodies' visual primitives over time and their poses.

The primitives are Foxglove's (``foxglove.SceneUpdate``): cubes, spheres and cylinders by their full
extents, triangle lists and lines by points, arrows by their pose (+x) and lengths, each with a pose in its
body's frame and an RGBA colour. The trace (runner.trace.scene) publishes every body as it is drawn at
t = 0 (entity ``body/<name>``, frame ``<name>``: a model's visuals, else its collision shapes), the
joints (``joint/<name>``), collision solids (``solid/<body>/<node>``, translucent), the collision shapes
of bodies drawn by their visuals (``collision/<name>`` on /scene/collision: layer ``collision``, not
drawn unless asked) and a new shape whenever an interval changes a body's scale, each replacing the
entity of the same id (Foxglove's rule). :func:`scene_model` reads those channels; when a trace has none
it can read (a cut-off partial trace), the collision shapes come from the ``body_specs`` metadata at
scale 1.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from reports import trace_format as tf
from reports.scene3d.scene_channel import read_scene_updates
from reports.trace_reader import Trace

__all__ = ["BodyTrack", "EntityVisual", "Primitive", "SceneModel", "entity_from_message", "scene_model"]

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # w, x, y, z
RGBA = tuple[float, float, float, float]

#: shape kinds of backends.types -> how a body without a readable scene channel is drawn
PLANE_EXTENT = 40.0  # metres, as the trace's /scene draws a plane
PLANE_THICKNESS = 0.01
DEFAULT_RGBA: RGBA = (0.7, 0.7, 0.7, 1.0)


@dataclass(frozen=True)
class Primitive:
    """One Foxglove primitive in its body's frame: ``cube``, ``sphere``, ``cylinder`` (along local z),
    ``triangles`` (``points`` taken three at a time), ``lines`` (a strip; ``closed`` for a loop) or ``arrow``
    (along its local +x from its position; ``size``: total length, shaft diameter, head diameter)."""

    kind: str
    rgba: RGBA
    position: Vec3 = (0.0, 0.0, 0.0)
    quat: Quat = (1.0, 0.0, 0.0, 0.0)
    size: Vec3 = (0.0, 0.0, 0.0)
    points: tuple[Vec3, ...] = ()
    closed: bool = False


@dataclass(frozen=True)
class EntityVisual:
    """A scene entity: primitives attached to one body's frame; ``solid`` for collision geometry (a collision
    solid, or a body's collision shapes: ``layer`` says which)."""

    id: str
    body: str
    primitives: tuple[Primitive, ...]
    solid: bool = False
    layer: str = "body"  # body | joint | solid | collision (drawn only when asked)


@dataclass
class BodyTrack:
    """A body's recorded pose at each time of ``times``; quaternions (w, x, y, z)."""

    times: np.ndarray  # (S,)
    pos: np.ndarray  # (S, 3)
    quat: np.ndarray  # (S, 4)

    def index(self, t: float) -> int:
        """The last recorded step at or before ``t`` (the first step before the run starts)."""
        k = int(np.searchsorted(self.times, t + 1e-9, side="right")) - 1
        return min(max(k, 0), len(self.times) - 1)


@dataclass
class SceneModel:
    """A run's scene: bodies (in trace order) with motion kind and colour, the entity updates in time
    order (each a time and the entities it sets; ``None`` deletes an id), and the recorded poses."""

    bodies: list[str]
    motion: dict[str, str]
    color: dict[str, RGBA]
    shape: dict[str, str]  # body -> shape kind (box, sphere, cylinder, capsule, plane)
    updates: list[tuple[float, dict[str, EntityVisual | None]]]
    tracks: dict[str, BodyTrack] = field(default_factory=dict)
    end_time: float = 0.0

    @classmethod
    def from_specs(cls, specs: Sequence[Mapping[str, Any]]) -> SceneModel:
        """A scene from ``body_specs`` (backends.types.BodySpec as dicts) alone: shapes at scale 1, no poses."""
        entities: dict[str, EntityVisual | None] = {}
        for s in specs:
            entities[f"body/{s['name']}"] = _spec_entity(s)
        return cls(
            bodies=[str(s["name"]) for s in specs],
            motion={str(s["name"]): str(s.get("motion", "dynamic")) for s in specs},
            color={str(s["name"]): _rgba(s.get("color")) for s in specs},
            shape={str(s["name"]): str(s["shape"]["kind"]) for s in specs},
            updates=[(0.0, entities)],
        )

    def add_update(self, t: float, entities: Sequence[EntityVisual]) -> None:
        """A live run's scene changes at ``t`` (each entity replaces the one of its id), in time order."""
        self.updates.append((t, {e.id: e for e in entities}))

    def entities_at(self, t: float) -> dict[str, EntityVisual]:
        """Every entity as the scene shows it at ``t``."""
        out: dict[str, EntityVisual] = {}
        for when, update in self.updates:
            if when > t + 1e-9:
                break
            for key, entity in update.items():
                if entity is None:
                    out.pop(key, None)
                else:
                    out[key] = entity
        return out

    def pose(self, body: str, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """(position, quaternion w x y z) of ``body`` at ``t``, None if it has no finite recorded pose."""
        track = self.tracks.get(body)
        if track is None or not len(track.times):
            return None
        k = track.index(t)
        p, q = track.pos[k], track.quat[k]
        if not (np.isfinite(p).all() and np.isfinite(q).all()):
            return None
        return p, q


def _rgba(color: Any) -> RGBA:
    if isinstance(color, Sequence) and len(color) >= 3:
        c = [float(x) for x in color]
        return (c[0], c[1], c[2], c[3] if len(c) > 3 else 1.0)
    return DEFAULT_RGBA


def _spec_entity(spec: Mapping[str, Any]) -> EntityVisual:
    """The primitives the trace writer publishes for a body shape (runner.trace.foxglove.body_primitives)."""
    name = str(spec["name"])
    return EntityVisual(f"body/{name}", name, tuple(_shape_prims(spec["shape"], _rgba(spec.get("color")), spec)))


def _placed(prims: list[Primitive], pos: Vec3, quat: Quat) -> list[Primitive]:
    """Primitives of a shape moved to its pose in the body frame (a compound body's shape)."""
    from backends.geometry import quat_mul, quat_rotate

    out = []
    for p in prims:
        x, y, z = quat_rotate(quat, p.position)
        out.append(replace(p, position=(x + pos[0], y + pos[1], z + pos[2]), quat=quat_mul(quat, p.quat)))
    return out


def _shape_prims(shape: Mapping[str, Any], rgba: RGBA, spec: Mapping[str, Any]) -> list[Primitive]:
    kind = shape["kind"]
    if kind == "compound":  # each shape at its local pose (backends.types.PlacedShape)
        out: list[Primitive] = []
        for placed in spec.get("shapes") or []:
            own = _rgba(placed["color"]) if placed.get("color") else rgba
            pos = tuple(float(c) for c in placed["pos"])
            quat = tuple(float(c) for c in placed["quat"])
            out += _placed(_shape_prims(placed["shape"], own, {}), pos, quat)  # type: ignore[arg-type]
        return out
    if kind in ("convex", "trimesh"):
        mesh = shape.get("mesh") or {"vertices": [], "faces": []}
        v = mesh["vertices"]
        points = tuple(tuple(float(c) for c in v[i]) for face in mesh["faces"] for i in face)
        return [Primitive("triangles", rgba, points=points)]  # type: ignore[arg-type]
    r, length = float(shape.get("radius", 0.0)), float(shape.get("length", 0.0))
    prims: list[Primitive] = []
    if kind == "box":
        size = tuple(float(c) for c in shape["size"])
        prims.append(Primitive("cube", rgba, size=(size[0], size[1], size[2])))
    elif kind == "sphere":
        prims.append(Primitive("sphere", rgba, size=(2 * r, 2 * r, 2 * r)))
    elif kind in ("cylinder", "capsule"):
        prims.append(Primitive("cylinder", rgba, size=(2 * r, 2 * r, length)))
        if kind == "capsule":
            for z in (length / 2, -length / 2):
                prims.append(Primitive("sphere", rgba, position=(0.0, 0.0, z), size=(2 * r, 2 * r, 2 * r)))
    elif kind == "plane":
        slab = (PLANE_EXTENT, PLANE_EXTENT, PLANE_THICKNESS)
        prims.append(Primitive("cube", rgba, position=(0.0, 0.0, -PLANE_THICKNESS / 2), size=slab))
    return prims


# ---- foxglove.SceneUpdate messages (as dicts with Foxglove's field names) -----------------------------------------


def _vec(v: Mapping[str, Any] | None) -> Vec3:
    v = v or {}
    return (float(v.get("x", 0.0)), float(v.get("y", 0.0)), float(v.get("z", 0.0)))


def _pose(p: Mapping[str, Any] | None) -> tuple[Vec3, Quat]:
    p = p or {}
    o = p.get("orientation") or {}
    q = (float(o.get("w", 0.0)), float(o.get("x", 0.0)), float(o.get("y", 0.0)), float(o.get("z", 0.0)))
    if not any(q):  # protobuf leaves an all-default quaternion out
        q = (1.0, 0.0, 0.0, 0.0)
    return _vec(p.get("position")), q


def _color(c: Mapping[str, Any] | None) -> RGBA:
    c = c or {}
    return (float(c.get("r", 0.0)), float(c.get("g", 0.0)), float(c.get("b", 0.0)), float(c.get("a", 0.0)))


_ARRAYS = {"cubes": "cube", "spheres": "sphere", "cylinders": "cylinder", "triangles": "triangles", "lines": "lines"}
_LINE_LOOP, _LINE_LIST = 1, 2
_LAYERS = {"solid": "solid", "collision": "collision", "joint": "joint"}  # by the entity id's first part


def _arrow(p: Mapping[str, Any]) -> Primitive:
    pos, quat = _pose(p.get("pose"))
    length = float(p.get("shaft_length", 0.0)) + float(p.get("head_length", 0.0))
    size = (length, float(p.get("shaft_diameter", 0.0)), float(p.get("head_diameter", 0.0)))
    return Primitive("arrow", _color(p.get("color")), pos, quat, size)


def entity_from_message(entity: Mapping[str, Any]) -> EntityVisual:
    """An :class:`EntityVisual` from one ``foxglove.SceneEntity`` (texts and models are not drawn); a line list
    becomes one two-point line per segment."""
    prims: list[Primitive] = []
    for array, kind in _ARRAYS.items():
        for p in entity.get(array) or []:
            pos, quat = _pose(p.get("pose"))
            points: tuple[Vec3, ...] = tuple(_vec(q) for q in p.get("points") or [])
            indices = [int(i) for i in p.get("indices") or []]
            if indices and points:
                points = tuple(points[i] for i in indices if 0 <= i < len(points))
            line_type = p.get("type", 0)
            closed = kind == "lines" and (line_type == _LINE_LOOP or line_type == "LINE_LOOP")
            rgba, size = _color(p.get("color")), _vec(p.get("size"))
            if kind == "lines" and line_type in (_LINE_LIST, "LINE_LIST"):
                pairs = range(0, len(points) - 1, 2)
                prims += [Primitive(kind, rgba, pos, quat, size, points[k : k + 2]) for k in pairs]
            else:
                prims.append(Primitive(kind, rgba, pos, quat, size, points, closed))
    prims += [_arrow(p) for p in entity.get("arrows") or []]
    meta = {str(m.get("key")): str(m.get("value")) for m in entity.get("metadata") or []}
    ident = str(entity.get("id", ""))
    layer = _LAYERS.get(ident.partition("/")[0], "solid" if "solid" in meta else "body")
    return EntityVisual(ident, str(entity.get("frame_id", "")), tuple(prims), layer in ("solid", "collision"), layer)


def _updates(messages: Sequence[tuple[float, Mapping[str, Any]]]) -> list[tuple[float, dict[str, EntityVisual | None]]]:
    out: list[tuple[float, dict[str, EntityVisual | None]]] = []
    known: set[str] = set()
    for t, msg in messages:
        update: dict[str, EntityVisual | None] = {}
        for d in msg.get("deletions") or []:
            if d.get("type", 0) in (1, "ALL"):
                update.update({k: None for k in known})
            else:
                update[str(d.get("id", ""))] = None
        for e in msg.get("entities") or []:
            visual = entity_from_message(e)
            update[visual.id] = visual
            known.add(visual.id)
        out.append((t, update))
    return out


def scene_model(trace: Trace) -> SceneModel:
    """The scene of ``trace``: shapes from its scene channel (else its metadata) and its recorded poses."""
    specs = [s for s in json.loads(trace.scenario.get(tf.KEY_BODY_SPECS, "[]")) if isinstance(s, dict)]
    model = SceneModel.from_specs(specs)
    messages = read_scene_updates(trace.path)
    if messages:
        model.updates = _updates(messages)
    for name in model.bodies:
        series = trace.bodies.get(name)
        if series is not None:
            model.tracks[name] = BodyTrack(trace.times, series.pos, series.quat)
    model.end_time = float(trace.times[-1]) if trace.times.size else 0.0
    return model
