"""Contact points as arrows (``trace: {contact_points: true}``): one ``foxglove.SceneUpdate`` per recorded step
on /contact_points (docs/trace-format.md).

Each point of ``Backend.contact_points()`` becomes an arrow in the world frame that starts at the point and
points along its normal (from body a to body b: the force on b), ``force * scale`` metres long; ``scale``
(m/N) is the scenario's ``trace.contact_arrow_scale``, by default :data:`ARROW_LENGTH` for the heaviest moving
body's weight, and is stated in the trace's scenario record (``contact_arrow_scale``) and in every entity's
metadata. The entity is replaced every step (one id), so a step without contacts shows no arrow.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from foxglove_schemas_protobuf.ArrowPrimitive_pb2 import ArrowPrimitive
from foxglove_schemas_protobuf.Color_pb2 import Color
from foxglove_schemas_protobuf.Pose_pb2 import Pose
from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3

from backends.types import CompiledWorld, ContactPoint, Motion
from reports.trace_format import WORLD_FRAME
from runner.trace import foxglove as fx

#: Metres of arrow for the heaviest moving body's weight (the default scale).
ARROW_LENGTH = 0.25
#: The default scale of a world with no weight to show (no gravity or no massive moving body): m/N.
FALLBACK_SCALE = 0.01
#: An arrow's head as a share of its length; its shaft's and head's diameters likewise (a thin arrow).
HEAD, SHAFT_WIDTH, HEAD_WIDTH = 0.25, 0.08, 0.2
ARROW_RGBA = (1.0, 0.25, 0.1, 1.0)
ENTITY_ID = "contact_points"
#: The scenario record's key for the scale (m/N).
KEY_SCALE = "contact_arrow_scale"


def default_scale(world: CompiledWorld) -> float:
    """m/N such that the heaviest moving body's weight is :data:`ARROW_LENGTH` long."""
    g = math.sqrt(sum(c * c for c in world.gravity))
    mass = max((b.mass for b in world.bodies if b.motion is Motion.DYNAMIC), default=0.0)
    weight = mass * g
    return ARROW_LENGTH / weight if weight > 0.0 and math.isfinite(weight) else FALLBACK_SCALE


def _x_to(n: Sequence[float]) -> Quaternion:
    """The rotation taking +x (a Foxglove arrow's direction) to the unit vector ``n`` (the shortest arc)."""
    x, y, z = (float(c) for c in n)
    w = 1.0 + x
    if w < 1e-9:  # n is -x: half a turn about z
        return Quaternion(x=0.0, y=0.0, z=1.0, w=0.0)
    qy, qz = -z, y  # +x cross n
    norm = math.sqrt(w * w + qy * qy + qz * qz)
    return Quaternion(x=0.0, y=qy / norm, z=qz / norm, w=w / norm)


def arrow(point: ContactPoint, scale: float) -> ArrowPrimitive | None:
    """``point``'s arrow, or None when its force is not a positive finite number (nothing to draw)."""
    length = point.force * scale
    if not (length > 0.0 and math.isfinite(length)):
        return None
    px, py, pz = point.pos
    r, g, b, a = ARROW_RGBA
    return ArrowPrimitive(
        pose=Pose(position=Vector3(x=px, y=py, z=pz), orientation=_x_to(point.normal)),
        shaft_length=length * (1.0 - HEAD), shaft_diameter=length * SHAFT_WIDTH,
        head_length=length * HEAD, head_diameter=length * HEAD_WIDTH, color=Color(r=r, g=g, b=b, a=a),
    )  # fmt: skip


def scene_update(ns: int, points: Sequence[ContactPoint], scale: float) -> fx.SceneUpdate:
    """The step's arrows as one world-frame entity (replacing the previous step's)."""
    arrows = [a for a in (arrow(p, scale) for p in points) if a is not None]
    meta = {KEY_SCALE: repr(float(scale)), "unit": "m/N", "points": str(len(points))}
    return fx.SceneUpdate(entities=[fx.entity(ns, WORLD_FRAME, ENTITY_ID, meta, arrows=arrows)])
