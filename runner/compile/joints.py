"""Joints: the stated zero of a joint's coordinate, and its stops converted to the backends' zero (the start).

Backends measure a slider's position and a hinge's angle from the start pose (backends/types.py). A scenario
may state its stops from another zero (``limits: {zero: absolute}``): the conversion is a constant offset,
the coordinate's absolute value at the start, computed here once:

* hinge: the rotation of the body relative to the other body (the world for ``environment``) about the
  axis, 0 when the two orientations are equal: the twist angle of ``conj(q_other) * q_body`` about the axis
  seen in the other's frame (swing-twist decomposition), in (-pi, pi];
* slider: the body's origin along the axis from ``anchor`` (a point fixed to the other body: by default the
  other body's origin, or the world origin for ``environment``).

A reading of ``<joint>.position`` is ``offset + (value from the start)``, so stops and readings share a zero.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

from backends.geometry import IDENTITY, quat_conj, quat_mul, quat_rotate
from backends.types import BodySpec, JointDynamics, Motor, Vec3
from runner.language.model_physics import Drive, Dynamics, Joint, Limits


def _dot(a: Vec3, b: Vec3) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def absolute_at_start(joint: Joint, axis: Vec3, bodies: Mapping[str, BodySpec]) -> float:
    """The joint coordinate's value at the start, measured from its absolute zero."""
    body = bodies[joint.bodies[0]]
    other = bodies.get(joint.bodies[1])  # None: the environment
    if joint.type == "hinge":
        q_other = other.quat if other is not None else IDENTITY
        relative = quat_mul(quat_conj(q_other), body.quat)
        local_axis = quat_rotate(quat_conj(q_other), axis)
        twist = 2.0 * math.atan2(_dot(relative[1:], local_axis), relative[0])
        return math.remainder(twist, 2.0 * math.pi)  # (-pi, pi]
    if joint.anchor is not None:
        origin = joint.anchor
    else:
        origin = other.pos if other is not None else (0.0, 0.0, 0.0)
    offset = (body.pos[0] - origin[0], body.pos[1] - origin[1], body.pos[2] - origin[2])
    return _dot(offset, axis)


def zero_offset(joint: Joint, axis: Vec3, bodies: Mapping[str, BodySpec]) -> float:
    """What to add to a coordinate measured from the start to read it from the joint's stated zero."""
    if isinstance(joint.limits, Limits) and joint.limits.zero == "absolute":
        return absolute_at_start(joint, axis, bodies)
    return 0.0


def stops(joint: Joint, offset: float) -> tuple[float | None, float | None]:
    """The stops from the start pose, as backends take them."""
    if joint.limits is None:
        return None, None
    lo, hi = (joint.limits.lo, joint.limits.hi) if isinstance(joint.limits, Limits) else joint.limits
    return lo - offset, hi - offset


def dynamics(model: JointDynamics, given: Dynamics | None) -> JointDynamics:
    """A joint's dynamics: the model's (NO_DYNAMICS for a hand-written joint), each field the scenario gives
    replacing it."""
    if given is None:
        return model
    fields = {"damping": given.damping, "frictionloss": given.friction, "armature": given.armature,
              "effort": given.effort, "velocity": given.velocity}  # fmt: skip
    return replace(model, **{k: v for k, v in fields.items() if v is not None})


def initial_motor(motor: Motor | None, dyn: JointDynamics, driven: bool) -> Motor | None:
    """The joint's motor at the start: the given one capped by the effort and velocity limits, or an idle
    one (fmax 0) for a servo (``driven``), which the runner commands every step. Damping and friction loss
    need none: every adapter's slider and hinge takes ``set_motor`` (an MJCF file's joint on MuJoCo, which has
    a motor only when the scenario gives it one, keeps MuJoCo's own damping and friction loss)."""
    if motor is not None:
        return Motor(*capped(motor.vel, motor.fmax, dyn))
    return Motor(0.0, 0.0) if driven else None


def drive_motor(drive: Drive | None) -> Motor | None:
    """The velocity motor a drive in velocity mode starts with (the other modes leave the motor off)."""
    if drive is None or drive.vel is None or drive.fmax is None:
        return None
    return Motor(drive.vel, drive.fmax)


def capped(vel: float, fmax: float, dyn: JointDynamics) -> tuple[float, float]:
    """A motor command within the joint's velocity and effort limits (docs/semantics.md, "Joint dynamics")."""
    if dyn.velocity is not None:
        vel = max(-dyn.velocity, min(dyn.velocity, vel))
    if dyn.effort is not None:
        fmax = min(fmax, dyn.effort)
    return vel, fmax
