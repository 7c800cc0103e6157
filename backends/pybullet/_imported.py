"""The built world read back from PyBullet (``Backend.imported_model``): getDynamicsInfo, getLinkState,
getCollisionShapeData and getJointInfo.

PyBullet's client caches a body's joint info when the body is created, so the stops the adapter set later
with changeDynamics are read after ``syncBodyInfo`` (which asks the server again). Bullet applies a link's
``jointDamping`` itself (an explicit torque before each step) but never its ``jointFriction``, ``jointMaxForce``
or ``jointMaxVelocity`` (stored only: ../shared/notes/robot-models.md, 3.3 and 3.4): those are reported as
None, what the engine does not hold.
"""

from __future__ import annotations

from typing import Any

from .._kit.imported import ascending, body, stops, unit
from ..geometry import quat_rotate
from ..types import CompiledWorld, ImportedBody, ImportedJoint, ImportedModel, JointKind, Motion
from ._build import Layout

_STORED_ONLY = "jointFriction, jointMaxForce and jointMaxVelocity: stored by pybullet, never applied"


def _kinds(p: Any) -> dict[int, JointKind]:
    return {p.JOINT_REVOLUTE: JointKind.HINGE, p.JOINT_PRISMATIC: JointKind.SLIDER,
            p.JOINT_SPHERICAL: JointKind.BALL, p.JOINT_FIXED: JointKind.FIXED}  # fmt: skip


def _inertial(p: Any, c: int, uid: int, link: int) -> tuple[tuple[float, ...], tuple[float, float, float, float]]:
    """The inertial frame (COM world position, orientation as (w, x, y, z)) as the engine computes it now.
    getJointInfo's axis is in this frame (Bullet keeps a link's joint axis in its COM frame) [checked: the
    world axis of pendulum5's turned inertials]; getLinkState's link-frame entries (4, 5) come back in single
    precision, the inertial frame's (0, 1) in double."""
    if link < 0:
        pos, xyzw = p.getBasePositionAndOrientation(uid, physicsClientId=c)
    else:
        state = p.getLinkState(uid, link, computeForwardKinematics=1, physicsClientId=c)
        pos, xyzw = state[0], state[1]
    return tuple(pos), (xyzw[3], xyzw[0], xyzw[1], xyzw[2])


def read_imported(p: Any, c: int, world: CompiledWorld, layout: Layout) -> ImportedModel:
    bodies: list[ImportedBody] = []
    for i, spec in enumerate(world.bodies):
        if spec.motion is not Motion.DYNAMIC:
            continue
        uid, link = layout.uid[i], layout.link[i]
        info = p.getDynamicsInfo(uid, link, physicsClientId=c)
        com_world, _ = _inertial(p, c, uid, link)
        shapes = len(p.getCollisionShapeData(uid, link, physicsClientId=c))
        bodies.append(body(spec, info[0], ascending(info[2]), com_world, shapes))
    p.syncBodyInfo(physicsClientId=c)
    kinds = _kinds(p)
    joints: list[ImportedJoint] = []
    for joint_spec, handle in zip(world.joints, layout.joints, strict=True):
        info = p.getJointInfo(handle.uid, handle.link, physicsClientId=c)
        kind = kinds.get(int(info[2]), JointKind.FIXED)
        if kind in (JointKind.HINGE, JointKind.SLIDER):
            _, orientation = _inertial(p, c, handle.uid, handle.link)
            axis = unit(quat_rotate(orientation, info[13]), handle.sign)
            lo, hi = (info[8], info[9]) if info[8] <= info[9] else (None, None)  # lower > upper: no limit
            lo, hi = stops(lo, hi, handle.sign)
            joints.append(ImportedJoint(joint_spec.name, kind, axis, lo, hi, float(info[6]), None, None, None))
        else:
            joints.append(ImportedJoint(joint_spec.name, kind, None, None, None, None, None, None, None))
    return ImportedModel("pybullet", tuple(bodies), tuple(joints), (_STORED_ONLY,))
