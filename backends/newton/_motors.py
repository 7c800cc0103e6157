"""ODE's velocity motor on Newton solvers that ignore a joint's effort limit (XPBD, Featherstone).

ODE's motor is a velocity row whose force is bounded by ``fmax``: it brings the coordinate's rate to ``vel`` in
one step when that takes at most ``fmax``, else pushes with ``fmax``. Newton's own velocity drive (``target_kd``
with ``effort_limit``) is not clamped by these solvers (docs/backends/newton.md, "Motors"), so the adapter
applies the motor as a generalised force (``Control.joint_f``) before each engine step of ``h``:

    F = clamp(m_eff * (vel - rate) / h - bias, -fmax, fmax)

``m_eff`` is the joint's effective mass (slider: the reduced mass of its two bodies; hinge: the moments of
inertia about the axis through the anchor, reduced) and ``bias`` what gravity and the step's one-step forces
push along the coordinate, for a joint to the world (between two bodies it is left out: uniform gravity moves
both). That is ODE's row exactly for a single body on a joint to the world without contacts; where contacts
or a chain hanging from the joint's body act along the coordinate the rate lags by what they push in a step.
Nothing here imports an engine.
"""

from __future__ import annotations

import numpy as np

from ..geometry import quat_matrices
from ..types import BodySpec, JointKind, Motion
from ._build import JointHandle


def effective_mass(handle: JointHandle, bodies: tuple[BodySpec, ...]) -> float:
    """The joint's effective mass (kg) or moment of inertia about its axis (kg m^2), at the start pose."""
    axis = np.asarray(handle.spec.axis, dtype=float)
    anchor = np.asarray(handle.spec.anchor, dtype=float)
    inverse = 0.0
    for i in (handle.child, handle.parent):
        if i is None or bodies[i].motion is not Motion.DYNAMIC:
            continue
        b = bodies[i]
        if handle.spec.kind is JointKind.SLIDER:
            inverse += 1.0 / b.mass
            continue
        r = quat_matrices(b.quat)
        tensor = r @ b.inertia_tensor() @ r.T
        arm = np.asarray(b.pos) + r @ np.asarray(b.com) - anchor
        perpendicular = arm - np.dot(arm, axis) * axis
        inverse += 1.0 / (float(axis @ tensor @ axis) + b.mass * float(perpendicular @ perpendicular))
    return 1.0 / inverse if inverse > 0.0 else 0.0


def bias(handle: JointHandle, body: BodySpec, com_world: np.ndarray, gravity: np.ndarray,
         applied: np.ndarray | None) -> float:  # fmt: skip
    """What gravity and the one-step force (``applied``: force, torque at the COM) push along Newton's coordinate
    of a joint to the world (its child ``body`` with its COM at ``com_world``)."""
    axis = np.asarray(handle.spec.axis, dtype=float)
    force = body.mass * gravity
    torque = np.zeros(3)
    if applied is not None:
        force = force + applied[:3]
        torque = applied[3:]
    if handle.spec.kind is JointKind.SLIDER:
        return float(force @ axis)
    arm = com_world - np.asarray(handle.spec.anchor, dtype=float)
    return float((np.cross(arm, force) + torque) @ axis)
