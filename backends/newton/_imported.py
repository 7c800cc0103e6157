"""The built world read back from Newton's ``Model`` (``Backend.imported_model``).

Per dynamic body: ``body_mass``, ``body_inertia`` (about the COM, body frame: its principal moments),
``body_com`` placed in the world by the state's ``body_q`` before any step, and the shapes on the body counted.
Per joint: the Newton joint type, its axis (``joint_axis``, in the parent's joint frame) rotated to the world
by the parent body's pose and ``joint_X_p``, and the limits. The adapter gives Newton no joint damping,
friction or effort limit (the runner's velocity motor carries them, and XPBD and Featherstone do not clamp an
effort limit), so those are None.
"""

from __future__ import annotations

import numpy as np

from .._kit.imported import body, principal, stops, unit
from ..geometry import quat_matrices
from ..types import CompiledWorld, ImportedBody, ImportedJoint, ImportedModel, JointKind, Motion
from ._build import Built

#: Newton keeps "no limit" as +-1e10 (ModelBuilder's default joint limits): at or beyond it, no stop
NO_LIMIT = 1e9
_NOT_HELD = "joint damping, friction loss and effort limits: the runner's velocity motor (a clamped joint force)"


def _rotation(xyzw: np.ndarray) -> np.ndarray:
    x, y, z, w = (float(v) for v in xyzw)
    return np.asarray(quat_matrices((w, x, y, z)))


def read_imported(world: CompiledWorld, built: Built, body_q: np.ndarray) -> ImportedModel:
    """``body_q``: the state's body poses before any step."""
    model = built.model
    mass, inertia, com = model.body_mass.numpy(), model.body_inertia.numpy(), model.body_com.numpy()
    shape_body = model.shape_body.numpy()
    bodies: list[ImportedBody] = []
    for spec, k in zip(world.bodies, built.body, strict=True):
        if spec.motion is not Motion.DYNAMIC:
            continue
        com_world = body_q[k, :3] + _rotation(body_q[k, 3:]) @ com[k]
        shapes = int(np.count_nonzero(shape_body == k))
        bodies.append(body(spec, float(mass[k]), principal(inertia[k]), com_world, shapes))
    axes, lower, upper = model.joint_axis.numpy(), model.joint_limit_lower.numpy(), model.joint_limit_upper.numpy()
    x_p, qd_start = model.joint_X_p.numpy(), model.joint_qd_start.numpy()
    joints = []
    for h in built.joints:
        kind = h.spec.kind
        if kind in (JointKind.FIXED, JointKind.BALL):
            joints.append(ImportedJoint(h.spec.name, kind, None, None, None, None, None, None, None))
            continue
        d = int(qd_start[h.index])
        parent = _rotation(body_q[built.body[h.parent], 3:]) if h.parent is not None else np.eye(3)
        axis = parent @ _rotation(x_p[h.index, 3:]) @ axes[d]
        lo, hi = (float(v) if abs(float(v)) < NO_LIMIT else None for v in (lower[d], upper[d]))
        lo, hi = stops(lo, hi, h.sign)
        joints.append(ImportedJoint(h.spec.name, kind, unit(axis, h.sign), lo, hi, None, None, None, None))
    return ImportedModel("newton", tuple(bodies), tuple(joints), (_NOT_HELD,))


__all__ = ["read_imported"]
