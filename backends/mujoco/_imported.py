"""The built world read back from MuJoCo (``Backend.imported_model``): the compiled mjModel's arrays.

``body_mass``, ``body_inertia`` (principal moments), the COM from ``xipos`` after ``mj_kinematics`` on a copy of
the data (the backend's own MjData is not touched), collidable geoms per body (``geom_bodyid`` with a
non-zero ``contype`` or ``conaffinity``; none with `<flag contact="disable"/>`), ``jnt_type``, ``xaxis``,
``jnt_range`` where ``jnt_limited``,
``dof_damping``, ``dof_frictionloss`` and ``jnt_actfrcrange`` where ``jnt_actfrclimited`` (MuJoCo has no
velocity limit). For an MJCF robot built from its file these are MuJoCo's own reading of the file.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from .._kit.imported import ascending, body, stops, unit
from ..types import CompiledWorld, ImportedBody, ImportedJoint, ImportedModel, JointKind, Motion

_KINDS = {int(mujoco.mjtJoint.mjJNT_HINGE): JointKind.HINGE, int(mujoco.mjtJoint.mjJNT_SLIDE): JointKind.SLIDER,
          int(mujoco.mjtJoint.mjJNT_BALL): JointKind.BALL}  # fmt: skip


def read_imported(m: Any, d: Any, world: CompiledWorld, layout: Any, sign: np.ndarray,
                  starts: np.ndarray) -> ImportedModel:  # fmt: skip
    """``sign``/``starts``: per world joint, MuJoCo's coordinate to the world's (``world = sign q - start``)."""
    data = mujoco.MjData(m)
    data.qpos[:] = d.qpos
    mujoco.mj_kinematics(m, data)
    collides = (m.geom_contype != 0) | (m.geom_conaffinity != 0)
    if int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_CONTACT):  # the file's <flag contact="disable"/>
        collides[:] = False
    bodies: list[ImportedBody] = []
    for i, spec in enumerate(world.bodies):
        if spec.motion is not Motion.DYNAMIC:
            continue
        b = int(layout.body_id[i])
        shapes = int(np.count_nonzero((m.geom_bodyid == b) & collides))
        bodies.append(body(spec, float(m.body_mass[b]), ascending(m.body_inertia[b]), data.xipos[b], shapes))
    joints: list[ImportedJoint] = []
    for k, joint_spec in enumerate(world.joints):
        j = int(layout.joint_id[k])
        if j < 0:  # a weld: MuJoCo has no joint there
            joints.append(ImportedJoint(joint_spec.name, JointKind.FIXED, None, None, None, None, None, None, None))
            continue
        kind = _KINDS.get(int(m.jnt_type[j]), JointKind.FIXED)
        dof = int(m.jnt_dofadr[j])
        if kind is JointKind.BALL:
            joints.append(ImportedJoint(joint_spec.name, kind, None, None, None, float(m.dof_damping[dof]),
                                        float(m.dof_frictionloss[dof]), None, None))  # fmt: skip
            continue
        s = float(sign[k])
        lo, hi = (float(m.jnt_range[j][0]), float(m.jnt_range[j][1])) if m.jnt_limited[j] else (None, None)
        lo, hi = stops(lo, hi, s, float(starts[k]))
        force = m.jnt_actfrcrange[j]
        effort = float(max(abs(force[0]), abs(force[1]))) if m.jnt_actfrclimited[j] else None
        joints.append(ImportedJoint(joint_spec.name, kind, unit(data.xaxis[j], s), lo, hi, float(m.dof_damping[dof]),
                                    float(m.dof_frictionloss[dof]), effort, None))  # fmt: skip
    return ImportedModel("mujoco", tuple(bodies), tuple(joints))
