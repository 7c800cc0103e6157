"""The built world read back from Drake's MultibodyPlant (``Backend.imported_model``).

Per dynamic body: ``default_mass``, ``default_spatial_inertia`` shifted to the COM (its principal moments),
the COM's world position from ``EvalBodyPoseInWorld`` in the context before any step, and
``GetCollisionGeometriesForBody`` counted. Per joint: the Drake joint's type, its axis (``revolute_axis`` /
``translation_axis``, expressed in the joint's parent frame) rotated to the world by that frame's pose, its
position limits and ``default_damping``. Drake has no dry joint friction; its joints' velocity limits are not
enforced by the discrete solver, and the actuator's effort limit is the adapter's velocity motor (``fmax``), so
those are None.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._kit.imported import body, principal, stops, unit
from ..types import CompiledWorld, ImportedBody, ImportedJoint, ImportedModel, JointKind, Motion
from ._build import Built

_KINDS = {"revolute": JointKind.HINGE, "prismatic": JointKind.SLIDER, "ball_rpy": JointKind.BALL,
          "weld": JointKind.FIXED}  # fmt: skip
_NOT_HELD = "velocity limits: not enforced by Drake's discrete solver; actuator effort limit: the motor's fmax"


def _body(plant: Any, context: Any, rigid: Any) -> tuple[float, tuple[float, float, float], Any, int]:
    """(mass, principal moments about the COM, COM in the world, collision geometries) as the plant holds them."""
    inertia = rigid.default_spatial_inertia()  # about the body origin, in the body frame
    com = inertia.get_com()
    central = inertia.Shift(com).CalcRotationalInertia().CopyToFullMatrix3()
    com_world = plant.EvalBodyPoseInWorld(context, rigid).multiply(com)
    shapes = len(plant.GetCollisionGeometriesForBody(rigid))
    return float(rigid.default_mass()), principal(central), np.asarray(com_world), shapes


def _joint(plant: Any, context: Any, name: str, joint: Any, sign: float) -> ImportedJoint:
    kind = _KINDS.get(joint.type_name(), JointKind.FIXED)
    if kind is JointKind.FIXED:
        return ImportedJoint(name, kind, None, None, None, None, None, None, None)
    damping = float(np.max(joint.default_damping_vector()))
    if kind is JointKind.BALL:
        return ImportedJoint(name, kind, None, None, None, damping, None, None, None)
    local = joint.revolute_axis() if kind is JointKind.HINGE else joint.translation_axis()
    rotation = joint.frame_on_parent().CalcPoseInWorld(context).rotation().matrix()
    lo, hi = stops(float(joint.position_lower_limits()[0]), float(joint.position_upper_limits()[0]), sign)
    return ImportedJoint(name, kind, unit(rotation @ np.asarray(local), sign), lo, hi, damping, None, None, None)


def read_imported(world: CompiledWorld, built: Built, context: Any) -> ImportedModel:
    """``context``: the plant's context before any step (the world's start poses, joints at q = 0)."""
    plant = built.plant
    bodies: list[ImportedBody] = []
    for spec, rigid in zip(world.bodies, built.bodies, strict=True):
        if spec.motion is Motion.DYNAMIC:
            mass, moments, com_world, shapes = _body(plant, context, rigid)
            bodies.append(body(spec, mass, moments, com_world, shapes))
    joints = [_joint(plant, context, h.spec.name, h.joint, h.sign) for h in built.joints]
    return ImportedModel("drake", tuple(bodies), tuple(joints), (_NOT_HELD,))
