"""The built world read back from DART (``Backend.imported_model``): BodyNode and Joint getters.

``getMass``, ``getInertia().getMoment()`` (about the COM, in the node's frame), ``getCOM`` (world),
``getShapeNodes`` with a collision aspect; per joint its type, ``getAxis`` turned into the world by the child
node's world rotation and ``getTransformFromChildBodyNode``, the position limits where ``areLimitsEnforced``
(DART keeps unenforced limits too: they are not stops), ``getDampingCoefficient``, ``getCoulombFriction`` and
``getVelocityUpperLimit``. The force limits carry the adapter's velocity motor (its fmax, SERVO actuator), so
they are not a limit of the model: effort is None.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._kit.imported import body, finite_or_none, principal, stops, unit
from ..types import CompiledWorld, ImportedBody, ImportedJoint, ImportedModel, JointKind, Motion

_KINDS = {"RevoluteJoint": JointKind.HINGE, "PrismaticJoint": JointKind.SLIDER, "BallJoint": JointKind.BALL,
          "WeldJoint": JointKind.FIXED, "UniversalJoint": JointKind.UNIVERSAL}  # fmt: skip


def read_imported(world: CompiledWorld, bodies: list[Any], joints: list[Any]) -> ImportedModel:
    """``bodies``/``joints``: the adapter's handles (``.node``; ``.joint`` and ``.sign``), in world order."""
    out: list[ImportedBody] = []
    for spec, handle in zip(world.bodies, bodies, strict=True):
        if spec.motion is not Motion.DYNAMIC:
            continue
        node = handle.node
        shapes = sum(1 for shape in node.getShapeNodes() if shape.hasCollisionAspect())
        out.append(body(spec, node.getMass(), principal(node.getInertia().getMoment()), node.getCOM(), shapes))
    read: list[ImportedJoint] = []
    for joint_spec, handle in zip(world.joints, joints, strict=True):
        joint = handle.joint
        kind = _KINDS.get(joint.getType(), JointKind.FIXED)
        if kind not in (JointKind.HINGE, JointKind.SLIDER):
            read.append(ImportedJoint(joint_spec.name, kind, None, None, None, None, None, None, None))
            continue
        child = joint.getChildBodyNode()
        rotation = np.asarray(child.getWorldTransform().rotation()) @ np.asarray(
            joint.getTransformFromChildBodyNode().rotation()
        )
        axis = unit(rotation @ np.asarray(joint.getAxis(), dtype=float), handle.sign)
        enforced = joint.areLimitsEnforced()
        lo, hi = stops(joint.getPositionLowerLimit(0) if enforced else None,
                       joint.getPositionUpperLimit(0) if enforced else None, handle.sign)  # fmt: skip
        read.append(ImportedJoint(joint_spec.name, kind, axis, lo, hi, float(joint.getDampingCoefficient(0)),
                                  float(joint.getCoulombFriction(0)), None,
                                  finite_or_none(joint.getVelocityUpperLimit(0))))  # fmt: skip
    return ImportedModel("dart", tuple(out), tuple(read))
