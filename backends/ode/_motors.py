"""The motors' side of a step: joint coordinates, ODE's limit state, the fudge factor and the force applied."""

from __future__ import annotations

import math
from typing import Any

from panda3d.core import Quat as PandaQuat

from ..types import JointKind
from ._build import JointHandle, axis_arg

_ROTATIONAL = (JointKind.HINGE, JointKind.UNIVERSAL)


def _dot(a: Any, b: Any) -> float:
    return float(a[0] * b[0] + a[1] * b[1] + a[2] * b[2])


def _inertia_along(body: Any, handle: JointHandle) -> float:
    """The body's inertia along the joint's coordinate: its mass for a slider, its moment about the
    joint's axis through the anchor for a hinge (the first axis of a universal joint)."""
    mass = body.getMass()
    if handle.spec.kind is JointKind.SLIDER:
        return float(mass.getMagnitude())
    j = handle.joint
    axis = j.getAxis() if handle.spec.kind is JointKind.HINGE else j.getAxis1()
    local = PandaQuat(body.getQuaternion()).conjugate().xform(axis)  # the axis in the body (COM) frame
    tensor = mass.getInertialTensor()
    about_com = sum(local[a] * tensor.getCell(a, b) * local[b] for a in range(3) for b in range(3))
    lever = (body.getPosition() - j.getAnchor()).cross(axis)
    return float(about_com + mass.getMagnitude() * lever.lengthSquared())


def effective_inertia(handle: JointHandle) -> float:
    """1 / (1/I1 + 1/I2) of the joint's two bodies along its coordinate (the environment: 1/I2 = 0), plus the
    joint's armature (its row adds a to the coordinate's inertia: 1 / J (M + a J^T J)^-1 J^T = 1 / J M^-1 J^T + a)."""
    inverse = 1.0 / _inertia_along(handle.body, handle)
    other = handle.joint.getBody(1)
    if other is not None and not other.isEmpty():
        inverse += 1.0 / _inertia_along(other, handle)
    return 1.0 / inverse + handle.spec.dynamics.armature


def coordinate(handle: JointHandle) -> tuple[float, float]:
    """The joint's position and rate along its coordinate (NaN for a joint without one)."""
    j, kind = handle.joint, handle.spec.kind
    if kind is JointKind.SLIDER:
        return j.getPosition(), j.getPositionRate()
    if kind is JointKind.HINGE:
        return j.getAngle(), j.getAngleRate()
    if kind is JointKind.UNIVERSAL:  # the first axis is the joint's coordinate
        return j.getAngle1(), j.getAngle1Rate()
    return math.nan, math.nan


def limit_state(handle: JointHandle) -> int:
    """ODE's limit state at the start of the step (dxJointLimitMotor::testRowActivation)."""
    spec = handle.spec
    if handle.fmax <= 0.0 or (spec.lo is None and spec.hi is None):
        return 0
    lo = -math.inf if spec.lo is None else spec.lo
    hi = math.inf if spec.hi is None else spec.hi
    if lo > hi or (spec.kind in _ROTATIONAL and lo < -math.pi and hi > math.pi):
        return 0
    pos = coordinate(handle)[0]
    return 1 if pos <= lo else 2 if pos >= hi else 0


def fudge_away(handle: JointHandle, limit: int, h: float) -> float | None:
    """At a stop with the motor powering away from it, ODE applies fmax x the fudge factor to the bodies
    for the step instead of its velocity row (``dxJointLimitMotor::addLimot``): with the fudge at 1
    (ODE's default) a motor reversed at its stop throws the joint far past its target rate for that
    step (a 1 kg bob on a 0.5 m lever, fmax 100 N m: -3.8 rad/s for a target of -1). The fudge is set
    so that fmax x fudge brings the joint's rate to the target in the step, from the effective inertia
    of the joint's own bodies about it (at most 1: never more than fmax). Bodies further along a chain
    only add inertia, so the step falls short rather than past, and the velocity row finishes the job
    the next step, off the stop.

    Returns the fudge factor as ODE stores it (float32), None when it was left as it was."""
    vel, fmax = handle.vel, handle.fmax
    if handle.feedback is None or fmax <= 0.0 or not ((limit == 1 and vel > 0.0) or (limit == 2 and vel < 0.0)):
        return None
    if handle.spec.lo == handle.spec.hi:
        return None  # both stops at once: ODE switches the motor off
    rate = coordinate(handle)[1]
    inertia = effective_inertia(handle)
    fudge = min(1.0, inertia * abs(vel - rate) / (fmax * h)) if math.isfinite(rate) else 1.0
    handle.joint.setParamFudgeFactor(*axis_arg(handle), fudge)
    return float(handle.joint.getParamFudgeFactor(*axis_arg(handle)))


def step_frame(handle: JointHandle) -> tuple[Any, Any] | None:
    """The joint's axis and the lever from its anchor to the body's COM at the start of the step: the
    geometry ODE builds the step's constraint rows with (``getInfo2``), hence its feedback's."""
    if handle.feedback is None or handle.fmax <= 0.0:
        return None
    j, kind = handle.joint, handle.spec.kind
    if kind is JointKind.SLIDER:
        return j.getAxis(), None
    axis = j.getAxis() if kind is JointKind.HINGE else j.getAxis1()
    return axis, handle.body.getPosition() - j.getAnchor()


def motor_force(handle: JointHandle, limit: int, frame: tuple[Any, Any] | None, fudge: float) -> float:
    """The force (torque) the motor applied along the joint's coordinate in the step just taken.

    Off a stop the motor is an LCP row and joint feedback has its force; at a stop ODE applies
    +-fmax (times the fudge factor when powering away) directly to the bodies, outside feedback.
    The feedback is resolved with the axis and lever of the step's start (``frame``): read after the
    step, a link turning at 3 rad/s under a 500 N joint force moves its lever by 3 mm in 10 ms and
    the torque read by 1.6 N m (kuka_arm: 301.6 N m from a row bounded at 300).
    """
    if handle.feedback is None or handle.fmax <= 0.0 or frame is None:
        return 0.0
    if limit:
        if handle.spec.lo == handle.spec.hi:
            return 0.0  # both stops at once: ODE switches the motor off
        fm = -handle.fmax if handle.vel > 0.0 or (handle.vel == 0.0 and limit == 2) else handle.fmax
        if (limit == 1 and handle.vel > 0.0) or (limit == 2 and handle.vel < 0.0):
            fm *= fudge
        return -fm
    fb = handle.feedback
    force = fb.getForce1()
    axis, r = frame
    if r is None:  # a slider
        return _dot(force, axis)
    # Moment about the anchor: the anchor rows' forces have none, the motor row is along the axis.
    return _dot(fb.getTorque1() + r.cross(force), axis)
