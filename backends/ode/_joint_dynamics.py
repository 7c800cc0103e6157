"""Joint armature and joint springs on ODE (``joint:armature``, ``joint:stiffness``; docs/backends/ode.md).

**Armature** a on a slider's or hinge's coordinate q: MuJoCo adds a to the joint's diagonal entry of the mass
matrix, so its semi-implicit Euler step solves (M + a J^T J) dv = h f, i.e. the bodies feel the extra
generalised force -a (qdot_new - qdot_old) / h along the coordinate. ODE solves every constraint row of a step
(step.cpp: A = J M^-1 J^T + CFM / h, rhs = c / h - J (v / h + M^-1 f_ext)) so that J v_new = c - CFM lambda,
lambda being the row's force. One more velocity row on the coordinate, unbounded, with c = qdot_old (the row's
rate at the step's start) and CFM = h / a, therefore has exactly lambda = -a (qdot_new - qdot_old) / h: the
armature, solved in the same LCP as the contacts, the stops and the joint's own motor (damping, friction loss,
a scenario's motor), so an impact or a bounded motor meets I + a. The row is a user-mode ``OdeAMotorJoint``
(hinge) or an ``OdeLMotorJoint`` (slider) between the joint's two bodies, its one axis fixed in the first body
(rel 1) as the joint's own axis: both go through ODE's ``dxJointLimitMotor::addLimot``, as the joint's own
motor row does, so its Jacobian is the motor row's (for a slider between two bodies with its linear torque
decoupling c x axis on both bodies, c half the line between their centres: then J v is the exact rate of
ODE's slider position while the bodies turn together; ``dJointGetSliderPositionRate`` omits that term, so the
rate is computed here). Its own CFM replaces the world's (``normal_cfm``); dParamFMax is dInfinity.

**Damping** c (``OdeBackend.native_damping``): the same row carries it implicitly. With target 0 and CFM 1 / c a
row has J v_new = -lambda / c, i.e. lambda = -c qdot_new exactly (MuJoCo's implicit damping, DART's): unbounded,
so no bounded row of the LCP depends on it, as the runner's motor with dParamFMax = c |qdot| did (on pybullet_data's
ant, armature 1 and damping 1, that bound made Dantzig fail a step, "LCP internal error, s <= 0"). With both a
and c the forces add, -a (qdot_new - qdot_old) / h - c qdot_new, one row: CFM = h / (a + c h) and the target
a qdot_old / (a + c h) (a damped rotor: qdot_new = qdot_old / (1 + c h / (I + a)) with no other force).

**Stiffness** k towards springref (counted from the start, where ODE's joint position is 0): the force
-k (q - springref) from the position at the start of each engine step (MuJoCo's Euler step takes its passive
force so), handed to ODE as ``dJointAddHingeTorque`` / ``dJointAddSliderForce``: J^T f for the joint's own
motor-row Jacobian, the generalised force on q and nothing else. A hinge's angle is unwrapped across ODE's
+-pi (the spring is the model's, not periodic).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from panda3d.ode import OdeAMotorJoint, OdeLMotorJoint, OdeWorld

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, JointKind
from ._build import JointHandle

#: ODE 0.13.1's parameter numbers (include/ode/common.h, D_ALL_PARAM_NAMES): OdeLMotorJoint has only the
#: numbered setParam (checked by a one-step momentum balance in tests/backends/test_ode_joint_dynamics.py).
PARAM_VEL, PARAM_FMAX, PARAM_CFM = 2, 5, 8
_ONE_DOF = (JointKind.HINGE, JointKind.SLIDER)


def check_joint_dynamics(world: CompiledWorld) -> None:
    """Refuse armature or stiffness on a joint other than a slider or hinge (a universal joint's) up front (the
    runner's joint dynamics damp sliders and hinges only, so damping elsewhere is no concern of this row)."""
    for spec in world.joints:
        if (spec.dynamics.armature > 0.0 or spec.dynamics.stiffness > 0.0) and spec.kind not in _ONE_DOF:
            raise UnsupportedFeature(
                f"Joint `{spec.name}` ({spec.kind.value}): backend `ode` maps armature and stiffness on sliders "
                "and hinges only."
            )


@dataclass
class _Rotor:
    """The armature-and-damping row of one joint: its motor joint and whether the joint is a slider between two
    bodies; ``share`` is a / (a + c h), the part of the armature's target the row aims at (1: no damping)."""

    handle: JointHandle
    motor: Any  # OdeAMotorJoint | OdeLMotorJoint
    slider_pair: bool
    share: float = 1.0
    #: a slider pair's row geometry (axis, p1, p2) at the last step's start; None: none yet (or a body was reset)
    previous: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


@dataclass
class _Spring:
    handle: JointHandle
    stiffness: float
    rest: float
    last: float = 0.0  # a hinge's angle as ODE read it last (0 at the start), in (-pi, pi]
    turns: int = 0  # whole turns ODE's angle wrapped since the start
    force: float = 0.0  # N or N m, from the position at the step's start


class JointDynamics:
    """Armature-and-damping rows and springs of a scene's sliders and hinges; ``before_step`` readies each engine
    step."""

    def __init__(self, world: OdeWorld, handles: list[JointHandle], h: float) -> None:
        self.h = h
        self.rotors: list[_Rotor] = []
        self.springs: list[_Spring] = []
        for handle in handles:  # check_joint_dynamics refused the other kinds
            dyn = handle.spec.dynamics
            if handle.spec.kind not in _ONE_DOF:
                continue
            if dyn.armature > 0.0 or dyn.damping > 0.0:
                self.rotors.append(_rotor(world, handle, dyn.armature, dyn.damping, h))
            if dyn.stiffness > 0.0:
                self.springs.append(_Spring(handle, dyn.stiffness, dyn.springref))

    def __bool__(self) -> bool:
        return bool(self.rotors or self.springs)

    def before_step(self) -> None:
        """Each armature or damping row's target: a / (a + c h) of the coordinate's rate now; each spring's force
        from the position now (applied by :meth:`add_forces`, once per ``dWorldStep``: ODE clears its force
        accumulators after each)."""
        for rotor in self.rotors:
            if rotor.share == 0.0:  # damping alone: the target stays 0 (_rotor)
                continue
            target = rotor.share * _target(rotor, self.h)
            if rotor.handle.spec.kind is JointKind.HINGE:
                rotor.motor.setParamVel(0, target)
            else:
                rotor.motor.setParam(PARAM_VEL, target)
        for spring in self.springs:
            joint = spring.handle.joint
            if spring.handle.spec.kind is JointKind.HINGE:
                angle = float(joint.getAngle())
                spring.turns -= round((angle - spring.last) / (2.0 * math.pi))  # a jump across +-pi: a wrap
                spring.last = angle
                spring.force = -spring.stiffness * (angle + 2.0 * math.pi * spring.turns - spring.rest)
            else:
                spring.force = -spring.stiffness * (joint.getPosition() - spring.rest)

    def add_forces(self) -> None:
        """The springs' forces of :meth:`before_step` on their joints (a trial step of ``_mimic`` adds them again)."""
        for spring in self.springs:
            if spring.handle.spec.kind is JointKind.HINGE:
                spring.handle.joint.addTorque(spring.force)
            else:
                spring.handle.joint.addForce(spring.force)

    def damping(self, handle: JointHandle) -> float:
        """The joint's damping as ODE holds it, c = 1 / CFM - a / h from its row's CFM (0: no damping in a row)."""
        for rotor in self.rotors:
            if rotor.handle is handle and rotor.share < 1.0:
                hinge = handle.spec.kind is JointKind.HINGE
                cfm = float(rotor.motor.getParamCFM(0) if hinge else rotor.motor.getParam(PARAM_CFM))
                return 1.0 / cfm - handle.spec.dynamics.armature / self.h
        return 0.0

    def forget(self) -> None:
        """A body was put somewhere new: the last step's geometry says nothing of the next one's."""
        for rotor in self.rotors:
            rotor.previous = None

    def destroy(self) -> None:
        for rotor in self.rotors:
            rotor.motor.destroy()
        self.rotors = []


def _rotor(world: OdeWorld, handle: JointHandle, armature: float, damping: float, h: float) -> _Rotor:
    """The unbounded velocity row with CFM h / (a + c h) on the joint's coordinate (see the module's docstring)."""
    cfm = h / (armature + damping * h)
    joint, other = handle.joint, handle.joint.getBody(1)
    two = other is not None and not other.isEmpty()
    axis = joint.getAxis()  # the world axis now, from the first body: stored in its frame as the joint's
    if handle.spec.kind is JointKind.HINGE:
        motor: Any = OdeAMotorJoint(world)
        motor.attach(handle.body, other if two else None)
        motor.setMode(0)  # dAMotorUser: the axes as given
        motor.setNumAxes(1)
        motor.setAxis(0, 1, axis)
        motor.setParamCFM(0, cfm)
        motor.setParamFMax(0, math.inf)
        motor.setParamVel(0, 0.0)  # damping alone aims at rest; with armature, before_step sets it
    else:
        motor = OdeLMotorJoint(world)
        motor.attach(handle.body, other if two else None)
        motor.setNumAxes(1)
        motor.setAxis(0, 1, axis)
        motor.setParam(PARAM_CFM, cfm)
        motor.setParam(PARAM_FMAX, math.inf)
        motor.setParam(PARAM_VEL, 0.0)
    return _Rotor(handle, motor, two and handle.spec.kind is JointKind.SLIDER, armature / (armature + damping * h))


def _target(rotor: _Rotor, h: float) -> float:
    """The armature row's target: the coordinate's rate now, J v, less the change that the bodies' motion alone
    makes to it over the step, h Jdot v, so that the row's force is -a qddot, the whole coordinate acceleration
    (MuJoCo's armature term), and not only -a J vdot.

    Hinge: ODE's own rate, the row's J v (Jdot v = (w1 x axis) . (w1 - w2) vanishes while the joint holds:
    w1 - w2 is along the axis). Slider to the environment: ODE's rate (its body cannot turn: Jdot = 0).
    Slider between two bodies: J v = axis . (v1 - v2) + (c x axis) . (w1 + w2), c = (p2 - p1) / 2 (addLimot's
    torque decoupling; ``dJointGetSliderPositionRate`` omits it, and it is the exact rate of ODE's slider
    position while the bodies turn together). On a rail turning at W, h Jdot v is the centripetal h W^2 y: the
    row then gives (m + a) yddot = m W^2 y, as MuJoCo. It is taken as what the last step's motion did to the
    row's rate at the velocities now, (J_k - J_k-1) v_k, which holds ERP's corrections of the rail's drift
    too (Jdot v from the state alone, used on the first step, left the rail's growth 2 % off at h = 1 ms)."""
    joint = rotor.handle.joint
    if rotor.handle.spec.kind is JointKind.HINGE:
        return float(joint.getAngleRate())
    if not rotor.slider_pair:
        return float(joint.getPositionRate())
    b1, b2 = joint.getBody(0), joint.getBody(1)
    geometry = (np.array(joint.getAxis(), float), np.array(b1.getPosition(), float), np.array(b2.getPosition(), float))
    v1, v2 = np.array(b1.getLinearVel(), float), np.array(b2.getLinearVel(), float)
    w1, w2 = np.array(b1.getAngularVel(), float), np.array(b2.getAngularVel(), float)
    rate = _row_rate(geometry, v1 - v2, w1 + w2)
    if rotor.previous is None:  # the first step (or after a reset): Jdot v from the state now
        axis, p1, p2 = geometry
        half, turning = 0.5 * (p2 - p1), np.cross(w1, axis)
        change = h * (turning @ (v1 - v2) + (np.cross(0.5 * (v2 - v1), axis) + np.cross(half, turning)) @ (w1 + w2))
    else:  # what the last step's motion did to the row's rate at today's velocities: ERP's corrections too
        change = rate - _row_rate(rotor.previous, v1 - v2, w1 + w2)
    rotor.previous = geometry
    return float(rate - change)


def _row_rate(geometry: tuple[np.ndarray, np.ndarray, np.ndarray], dv: np.ndarray, sw: np.ndarray) -> float:
    """J v of a slider pair's row with the geometry (axis, p1, p2), dv = v1 - v2, sw = w1 + w2."""
    axis, p1, p2 = geometry
    return float(axis @ dv + np.cross(0.5 * (p2 - p1), axis) @ sw)


def motor_row_rate(handle: JointHandle) -> float:
    """J v of the joint's motor row, whose J^T f is what ``dJointAddHingeTorque`` / ``dJointAddSliderForce`` apply:
    a hinge's ``getAngleRate``; a slider's rate with the linear torque decoupling of a slider between two bodies
    (``_row_rate``), the exact rate of ODE's slider position while the bodies turn together."""
    joint = handle.joint
    if handle.spec.kind is JointKind.HINGE:
        return float(joint.getAngleRate())
    b1, b2 = joint.getBody(0), joint.getBody(1)
    if b2 is None or b2.isEmpty():
        return float(joint.getPositionRate())
    geometry = (np.array(joint.getAxis(), float), np.array(b1.getPosition(), float), np.array(b2.getPosition(), float))
    dv = np.array(b1.getLinearVel(), float) - np.array(b2.getLinearVel(), float)
    return _row_rate(geometry, dv, np.array(b1.getAngularVel(), float) + np.array(b2.getAngularVel(), float))
