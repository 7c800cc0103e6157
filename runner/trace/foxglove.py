"""JSON Schemas of the trace's channels, and small builders for the Foxglove messages.

The Foxglove schemas (``foxglove.FrameTransforms``, ``foxglove.SceneUpdate``, ``foxglove.Log``) are
written from Foxglove's documented field lists for the JSON encoding: times are ``{"sec", "nsec"}``,
quaternions ``{x, y, z, w}``, colours ``{r, g, b, a}`` in 0..1, enums as integers. Foxglove
recognises a schema by its exact name (reports.trace_format.SCHEMA_*). The builders emit every field
of a primitive or entity (empty arrays included) so a strict consumer never meets a missing field.

The project's own channels get schemas built from the scenario's names, so Foxglove can complete
message paths such as ``/bodies.box.pos.z``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from reports.trace_format import JOINT_FIELDS, VALUE_RESOLUTION, WORLD_FRAME

# ---- building blocks ------------------------------------------------------------------------------


def _obj(title: str, description: str = "", /, **props: Any) -> dict[str, Any]:
    schema: dict[str, Any] = {"title": title, "type": "object", "properties": props}
    if description:
        schema["description"] = description
    return schema


def _array(items: Mapping[str, Any]) -> dict[str, Any]:
    return {"type": "array", "items": dict(items)}


def _enum(title: str, values: Mapping[str, int]) -> dict[str, Any]:
    return {"title": title, "oneOf": [{"title": k, "const": v} for k, v in values.items()]}


_NUM = {"type": "number"}
_OPT_NUM = {"type": ["number", "null"]}
_STR = {"type": "string"}
_BOOL = {"type": "boolean"}
_UINT = {"type": "integer", "minimum": 0}
_NSEC = {"type": "integer", "minimum": 0, "maximum": 999_999_999}

TIME = _obj("time", sec=_UINT, nsec=_NSEC)
DURATION = _obj("duration", sec={"type": "integer"}, nsec=_NSEC)
VECTOR3 = _obj("foxglove.Vector3", x=_NUM, y=_NUM, z=_NUM)
POINT3 = _obj("foxglove.Point3", x=_NUM, y=_NUM, z=_NUM)
QUATERNION = _obj("foxglove.Quaternion", x=_NUM, y=_NUM, z=_NUM, w=_NUM)
POSE = _obj("foxglove.Pose", position=VECTOR3, orientation=QUATERNION)
_UNIT = {"type": "number", "minimum": 0, "maximum": 1}
COLOR = _obj("foxglove.Color", r=_UNIT, g=_UNIT, b=_UNIT, a=_UNIT)
KEY_VALUE = _obj("foxglove.KeyValuePair", key=_STR, value=_STR)

FRAME_TRANSFORM = _obj(
    "foxglove.FrameTransform", "A transform between two reference frames in 3D space",
    timestamp=TIME, parent_frame_id=_STR, child_frame_id=_STR, translation=VECTOR3, rotation=QUATERNION,
)  # fmt: skip
FRAME_TRANSFORMS = _obj("foxglove.FrameTransforms", "An array of FrameTransform", transforms=_array(FRAME_TRANSFORM))

_POINTS, _COLORS, _INDICES = _array(POINT3), _array(COLOR), _array(_UINT)
ARROW = _obj(
    "foxglove.ArrowPrimitive",
    pose=POSE, shaft_length=_NUM, shaft_diameter=_NUM, head_length=_NUM, head_diameter=_NUM, color=COLOR,
)  # fmt: skip
CUBE = _obj("foxglove.CubePrimitive", pose=POSE, size=VECTOR3, color=COLOR)
SPHERE = _obj("foxglove.SpherePrimitive", pose=POSE, size=VECTOR3, color=COLOR)
CYLINDER = _obj("foxglove.CylinderPrimitive", pose=POSE, size=VECTOR3, bottom_scale=_NUM, top_scale=_NUM, color=COLOR)
LINE = _obj(
    "foxglove.LinePrimitive",
    type=_enum("foxglove.LineType", {"LINE_STRIP": 0, "LINE_LOOP": 1, "LINE_LIST": 2}),
    pose=POSE, thickness=_NUM, scale_invariant=_BOOL, points=_POINTS, color=COLOR, colors=_COLORS, indices=_INDICES,
)  # fmt: skip
TRIANGLES = _obj(
    "foxglove.TriangleListPrimitive", pose=POSE, points=_POINTS, color=COLOR, colors=_COLORS, indices=_INDICES
)
TEXT = _obj(
    "foxglove.TextPrimitive",
    pose=POSE, billboard=_BOOL, font_size=_NUM, scale_invariant=_BOOL, color=COLOR, text=_STR,
)  # fmt: skip
MODEL = _obj(
    "foxglove.ModelPrimitive",
    pose=POSE, scale=VECTOR3, color=COLOR, override_color=_BOOL, url=_STR, media_type=_STR,
    data={"type": "string", "contentEncoding": "base64"},
)  # fmt: skip
ENTITY_ARRAYS = ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models")
_PRIMITIVES = (ARROW, CUBE, SPHERE, CYLINDER, LINE, TRIANGLES, TEXT, MODEL)
SCENE_ENTITY = _obj(
    "foxglove.SceneEntity",
    timestamp=TIME, frame_id=_STR, id=_STR, lifetime=DURATION, frame_locked=_BOOL, metadata=_array(KEY_VALUE),
    **{name: _array(p) for name, p in zip(ENTITY_ARRAYS, _PRIMITIVES, strict=True)},
)  # fmt: skip
_DELETION_TYPE = _enum("foxglove.SceneEntityDeletionType", {"MATCHING_ID": 0, "ALL": 1})
SCENE_ENTITY_DELETION = _obj("foxglove.SceneEntityDeletion", timestamp=TIME, type=_DELETION_TYPE, id=_STR)
SCENE_UPDATE = _obj(
    "foxglove.SceneUpdate", "An update to the entities displayed in a 3D scene",
    deletions=_array(SCENE_ENTITY_DELETION), entities=_array(SCENE_ENTITY),
)  # fmt: skip
_LEVEL = _enum("foxglove.LogLevel", {"UNKNOWN": 0, "DEBUG": 1, "INFO": 2, "WARNING": 3, "ERROR": 4, "FATAL": 5})
LOG = _obj(
    "foxglove.Log", "A log message", timestamp=TIME, level=_LEVEL, message=_STR, name=_STR, file=_STR, line=_UINT
)

# ---- the project's channels ---------------------------------------------------------------------

_VEC = _obj("Vector3", x=_OPT_NUM, y=_OPT_NUM, z=_OPT_NUM)
_QUAT_WXYZ = _obj("Quaternion (w, x, y, z)", w=_OPT_NUM, x=_OPT_NUM, y=_OPT_NUM, z=_OPT_NUM)
BODY_STATE = _obj("BodyState", "world frame, SI", pos=_VEC, quat=_QUAT_WXYZ, vel=_VEC, angvel=_VEC)
JOINT_STATE = _obj("JointState", position=_OPT_NUM, velocity=_OPT_NUM, motor_force=_OPT_NUM)
_PAIR = _obj("ContactPair", a=_STR, b=_STR, points=_UINT, depth=_OPT_NUM, normal_force=_OPT_NUM)
CONTACTS = _obj("physics_scenarios.Contacts", count=_UINT, pairs=_array(_PAIR))
EVENT = _obj("physics_scenarios.Event", time=_NUM, name=_STR, source=_STR, detail={"type": "object"})
_ACTION = {"enum": ["start", "stop"]}
SOUND = _obj("physics_scenarios.Sound", time=_NUM, name=_STR, action=_ACTION, offset=_NUM, volume=_NUM)
VERDICTS = _obj("physics_scenarios.Verdicts", time=_NUM, verdicts=_array({"type": "object"}))


def bodies_schema(names: Iterable[str]) -> dict[str, Any]:
    return _obj("physics_scenarios.Bodies", "per-body state after the step", **{n: BODY_STATE for n in names})


def joints_schema(names: Iterable[str]) -> dict[str, Any]:
    return _obj("physics_scenarios.Joints", "per-joint state after the step", **{n: JOINT_STATE for n in names})


def state_schema(names: Iterable[str]) -> dict[str, Any]:
    value = {"type": ["boolean", "number", "string", "null"]}
    return _obj("physics_scenarios.State", "scenario state variables", **{n: value for n in names})


def json_safe(obj: Any) -> Any:
    """``obj`` made JSON-safe: non-finite floats -> None, numpy scalars and arrays -> Python values."""
    if isinstance(obj, float | np.floating):
        x = float(obj)
        return x if math.isfinite(x) else None
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, Mapping):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple | np.ndarray):
        return [json_safe(v) for v in obj]
    return obj


def json_number(x: float) -> str:
    """A float as JSON text: its shortest repr, or null for NaN and infinities."""
    return repr(float(x)) if math.isfinite(x) else "null"


def dumps(obj: Any, **kw: Any) -> str:
    """Compact JSON with NaN and infinities as null, numpy values as Python ones, anything else as str()."""
    try:  # the common case, entirely in the C encoder
        return json.dumps(obj, separators=(",", ":"), allow_nan=False, **kw)
    except (TypeError, ValueError):
        return json.dumps(json_safe(obj), separators=(",", ":"), allow_nan=False, default=str, **kw)


def schema_bytes(schema: Mapping[str, Any]) -> bytes:
    return json.dumps(schema, separators=(",", ":")).encode()


# ---- message builders ---------------------------------------------------------------------------


def stamp(ns: int) -> dict[str, int]:
    sec, nsec = divmod(ns, 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def vec3(v: Sequence[float]) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def pose(position: Sequence[float] = (0.0, 0.0, 0.0)) -> dict[str, Any]:
    """A pose at ``position`` with the identity orientation."""
    return {"position": vec3(position), "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}


def color(rgba: Sequence[float]) -> dict[str, float]:
    return {"r": float(rgba[0]), "g": float(rgba[1]), "b": float(rgba[2]), "a": float(rgba[3])}


def cube(size: Sequence[float], rgba: Sequence[float], center: Sequence[float] = (0, 0, 0)) -> dict[str, Any]:
    return {"pose": pose(center), "size": vec3(size), "color": color(rgba)}


def sphere(radius: float, rgba: Sequence[float], center: Sequence[float] = (0, 0, 0)) -> dict[str, Any]:
    d = 2.0 * radius
    return {"pose": pose(center), "size": vec3((d, d, d)), "color": color(rgba)}


def cylinder(
    radius: float, length: float, rgba: Sequence[float], center: Sequence[float] = (0, 0, 0)
) -> dict[str, Any]:
    """A cylinder along the local z axis, as the engine-neutral shapes define it."""
    d = 2.0 * radius
    return {
        "pose": pose(center),
        "size": vec3((d, d, length)),
        "bottom_scale": 1.0,
        "top_scale": 1.0,
        "color": color(rgba),
    }


def triangles(points: Sequence[Sequence[float]], rgba: Sequence[float]) -> dict[str, Any]:
    return {"pose": pose(), "points": [vec3(p) for p in points], "color": color(rgba), "colors": [], "indices": []}


def line_loop(points: Sequence[Sequence[float]], rgba: Sequence[float], thickness: float = 2.0) -> dict[str, Any]:
    """A closed outline, ``thickness`` in pixels."""
    return {
        "type": 1,
        "pose": pose(),
        "thickness": thickness,
        "scale_invariant": True,
        "points": [vec3(p) for p in points],
        "color": color(rgba),
        "colors": [],
        "indices": [],
    }


def entity(
    ns: int, frame_id: str, entity_id: str, metadata: Mapping[str, str] | None = None, **primitives: list[Any]
) -> dict[str, Any]:
    """A frame-locked, never-expiring SceneEntity; ``primitives`` by array name (cubes=[...], ...)."""
    unknown = set(primitives) - set(ENTITY_ARRAYS)
    if unknown:
        raise ValueError(f"unknown SceneEntity arrays {sorted(unknown)}; expected some of {ENTITY_ARRAYS}")
    out: dict[str, Any] = {
        "timestamp": stamp(ns),
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": True,
        "metadata": [{"key": k, "value": v} for k, v in (metadata or {}).items()],
    }
    for name in ENTITY_ARRAYS:
        out[name] = primitives.get(name, [])
    return out


PLANE_EXTENT = 40.0  # metres: a plane is shown as a large thin cube whose top face is the plane
PLANE_THICKNESS = 0.01
SOLID_RGBA = (1.0, 0.8, 0.1, 0.3)  # collision solids: translucent amber
SOLID_OUTLINE_RGBA = (1.0, 0.8, 0.1, 0.9)


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


def solid_primitives(
    kind: str,
    center: Sequence[float],
    radius: float,
    size: Sequence[float],
    vertices: Sequence[Sequence[float]],
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


def log(ns: int, level: int, message: str, name: str) -> dict[str, Any]:
    return {"timestamp": stamp(ns), "level": level, "message": message, "name": name, "file": "", "line": 0}


# ---- per-step messages ----------------------------------------------------------------------------

_EXP = round(-math.log10(VALUE_RESOLUTION))
_SCALE = 10.0**_EXP
_LIMIT = 1e9  # |value| below this fits an int64 once scaled by 1e9


class StepTemplate:
    """A JSON message whose numbers are filled in per step; the skeleton is serialised once.

    Values go in as integers of nanounits (``123456789e-9``, a valid JSON number), which formats about
    ten times faster than a float's shortest repr, at the fixed resolution ``VALUE_RESOLUTION``; a
    message with a non-finite or huge value (|x| >= 1e9) falls back to ``repr`` with ``null``.
    """

    _MARK = "\x01"  # a value slot
    STAMP = "\x02"  # the step's timestamp

    def __init__(self, skeleton: Any, n_values: int) -> None:
        text = json.dumps(skeleton, separators=(",", ":")).replace("%", "%%")
        parts = text.split(json.dumps(self._MARK))
        if len(parts) != n_values + 1:
            raise ValueError("names must not contain control characters")
        self._stamp = json.dumps(self.STAMP)
        self._fast = f"%de-{_EXP}".join(parts)
        self._slow = "%s".join(parts)

    def render(self, values: np.ndarray, stamp: str = "") -> str:
        if values.size and np.isfinite(values).all() and np.abs(values).max() < _LIMIT:
            fast = self._fast.replace(self._stamp, stamp) if stamp else self._fast
            return fast % tuple(np.rint(values * _SCALE).astype(np.int64).tolist())
        slow = self._slow.replace(self._stamp, stamp) if stamp else self._slow
        return slow % tuple(json_number(v) for v in values.tolist())

    @classmethod
    def slots(cls, keys: Iterable[str]) -> dict[str, str]:
        return {k: cls._MARK for k in keys}


_PAIR_FAST = f'{{"a":%s,"b":%s,"points":%d,"depth":%de-{_EXP},"normal_force":%de-{_EXP}}}'
_PAIR_SLOW = '{"a":%s,"b":%s,"points":%d,"depth":%s,"normal_force":%s}'


def contacts_message(pairs: Sequence[tuple[int, int, int, float, float]], quoted: Sequence[str]) -> str:
    """The /contacts message of one step; ``pairs`` = (a, b, points, depth, normal_force) rows (backends'
    ``Contact``), ``quoted`` = body names already JSON-encoded. Depth and force at ``VALUE_RESOLUTION``,
    like /bodies; a step with a non-finite or huge value writes shortest reprs, NaN and inf as null."""
    if not pairs:
        return '{"count":0,"pairs":[]}'
    a, b, points, depth, force = zip(*pairs, strict=True)
    values = np.array((depth, force), dtype=np.float64)
    if np.isfinite(values).all() and np.abs(values).max() < _LIMIT:
        depth_i, force_i = np.rint(values * _SCALE).astype(np.int64).tolist()
        rows = zip([quoted[i] for i in a], [quoted[i] for i in b], points, depth_i, force_i, strict=True)
        text = ",".join([_PAIR_FAST % row for row in rows])
    else:
        rows = zip(a, b, points, depth, force, strict=True)
        text = ",".join(
            [_PAIR_SLOW % (quoted[i], quoted[j], k, json_number(d), json_number(f)) for i, j, k, d, f in rows]
        )
    return f'{{"count":{len(pairs)},"pairs":[{text}]}}'


def step_templates(bodies: Sequence[str], joints: Sequence[str]) -> tuple[StepTemplate, StepTemplate, StepTemplate]:
    """Templates of the /tf, /bodies and /joints messages.

    Value order: /tf per body translation x y z, rotation x y z w; /bodies per body pos x y z,
    quat w x y z, vel x y z, angvel x y z; /joints per joint position, velocity, motor_force.
    """
    xyz, slot = "xyz", StepTemplate.slots
    frames = [
        {"timestamp": StepTemplate.STAMP, "parent_frame_id": WORLD_FRAME, "child_frame_id": b,
         "translation": slot(xyz), "rotation": slot("xyzw")}
        for b in bodies
    ]  # fmt: skip
    states = {b: {"pos": slot(xyz), "quat": slot("wxyz"), "vel": slot(xyz), "angvel": slot(xyz)} for b in bodies}
    return (
        StepTemplate({"transforms": frames}, 7 * len(bodies)),
        StepTemplate(states, 13 * len(bodies)),
        StepTemplate({j: slot(JOINT_FIELDS) for j in joints}, 3 * len(joints)),
    )
