"""Joint armature on PyBullet: a rotor geared 1:1 to the joint.

MuJoCo's armature ``a`` adds ``a`` to the joint's diagonal entry of the mass matrix and nothing else: the
kinetic energy gains ``a qdot^2 / 2``, as of a rotor whose own rate is exactly ``qdot`` and which is fixed in
the world (a rotor carried by the robot would add ``a`` to its ancestors' entries too: "inertia added to the
child body" is not armature). PyBullet has no armature, but it has gear constraints between the joints of
two multibodies (``JOINT_GEAR``, btMultiBodyGearConstraint: ``rate_a + ratio * rate_b = 0``, solved with the
contacts and motors, equal and opposite impulses on both). So each slider or hinge with armature gets its own
multibody: a fixed base and one link on a hinge (a slider for a slider) with moment ``a`` about its axis (mass
``a`` for a slider, moving across gravity so gravity does no work on it), no shapes, no damping, geared at
ratio -1 (equal rates) to the joint from its start rate. Measured: a 0.04 kg m^2 wheel at 10 rad/s geared
to an equal rotor at rest turns at 5.000 rad/s after one step (momentum kept), and a pendulum's period is
2 pi sqrt((I + a) / (m g L)) (tests/sim/test_joint_dynamics.py).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..geometry import quat_matrices
from ..types import CompiledWorld, JointKind
from ._build import Layout

#: a hinge rotor's mass and its moments across the axis: PyBullet needs positive ones; the joint holds them
_IDLE = 1e-9
#: the gear's force bound: the constraint, not a motor (far above any force a scenario produces)
_GEAR_FORCE = 1e12
#: Bullet's Gauss-Seidel sweeps over the non-contact rows (``numNonContactInnerIterations``, 1 by default) in a
#: world with a light geared joint (below). A gear row's effective mass is 1 / (1/M_jj + 1/a), M_jj the joint's
#: own inertia without armature (what it carries, about its axis); where a >> M_jj, neighbouring gears are coupled
#: through the links' joint-space inertia almost as strongly as each is to its own rotor, and one sweep leaves
#: them slipping: after pybullet_data's thrower's first step under gravity (a/M_jj up to 2.3e9: links of 1.7e-9
#: to 2.8e-8 kg, 0.75 kg m^2 rotors) its forearm-roll and wrist-roll joints turned at 0.031 and -0.082 rad/s while
#: their rotors stayed below 5e-6 rad/s (the watchdog read the 2.9 mJ the rotors should then carry as a gain).
#: More outer iterations do not help (1 to 5000 gave the same rates); inner sweeps do: measured on that step,
#: 0.031 rad/s at 1 sweep, 0.014 at 10, 0.0019 at 30 (0.905 per sweep), below 5e-6 at 100.
ROTOR_SWEEPS = 100
#: a/M_jj above which a geared joint is light. The sweeps are not free where contacts abound (humanoid_CMU,
#: a/M_jj <= 329, landing: 158 ms per step at 100 sweeps, 8.7 at 1), so only a world with such a joint gets them.
#: Measured a/M_jj (MuJoCo's mass matrix): ran with one sweep ant 124, humanoid_CMU 329, pybullet_data's reacher
#: 5.6e3; slipped pusher 9.9e7 (its object and target slides) and thrower 2.3e9. 1e6 lies between, 2.5 decades
#: from each.
LIGHT_GEAR = 1e6


def _across(gravity: tuple[float, float, float]) -> list[float]:
    """A unit axis perpendicular to gravity (any, without gravity): a slider rotor moves along it."""
    g = math.sqrt(sum(c * c for c in gravity))
    if g == 0.0:
        return [1.0, 0.0, 0.0]
    ux, uy, uz = (c / g for c in gravity)
    x, y, z = (0.0, -uz, uy) if abs(ux) < 0.9 else (-uy, ux, 0.0)  # u x e_x, or u x e_z
    n = math.sqrt(x * x + y * y + z * z)
    return [x / n, y / n, z / n]


def add_rotors(p: Any, c: int, world: CompiledWorld, layout: Layout, rates: dict[int, float]) -> list[int]:
    """One geared rotor multibody per slider or hinge with armature; ``rates``: each joint's start rate in
    PyBullet's coordinate. Returns the rotors' body ids; with a light one (armature above
    :data:`LIGHT_GEAR` times the joint's own inertia), the solver sweeps the gears :data:`ROTOR_SWEEPS` times."""
    rotors, geared = [], []
    for k, spec in enumerate(world.joints):
        armature, handle = spec.dynamics.armature, layout.joints[k]
        if armature <= 0.0 or spec.kind not in (JointKind.HINGE, JointKind.SLIDER) or handle.dofs != 1:
            continue
        hinge = spec.kind is JointKind.HINGE
        axis = [0.0, 0.0, 1.0] if hinge else _across(world.gravity)
        uid = int(
            p.createMultiBody(
                baseMass=0.0,
                linkMasses=[_IDLE if hinge else armature],
                linkCollisionShapeIndices=[-1],
                linkVisualShapeIndices=[-1],
                linkPositions=[[0.0, 0.0, 0.0]],
                linkOrientations=[[0.0, 0.0, 0.0, 1.0]],
                linkInertialFramePositions=[[0.0, 0.0, 0.0]],
                linkInertialFrameOrientations=[[0.0, 0.0, 0.0, 1.0]],
                linkParentIndices=[0],
                linkJointTypes=[p.JOINT_REVOLUTE if hinge else p.JOINT_PRISMATIC],
                linkJointAxis=[axis],
                physicsClientId=c,
            )
        )
        moments = [_IDLE, _IDLE, armature] if hinge else [_IDLE] * 3
        p.changeDynamics(uid, 0, localInertiaDiagonal=moments, physicsClientId=c)
        for key, value in (("linearDamping", 0.0), ("angularDamping", 0.0)):  # alone: see the backend's build
            p.changeDynamics(uid, -1, physicsClientId=c, **{key: value})
        p.changeDynamics(uid, 0, maxJointVelocity=1e6, physicsClientId=c)
        p.setJointMotorControl2(uid, 0, p.VELOCITY_CONTROL, force=0.0, physicsClientId=c)  # no default motor
        p.resetJointState(uid, 0, 0.0, rates.get(k, 0.0), physicsClientId=c)
        gear = p.createConstraint(handle.uid, handle.link, uid, 0, p.JOINT_GEAR, [0.0, 1.0, 0.0], [0.0, 0.0, 0.0],
                                  [0.0, 0.0, 0.0], physicsClientId=c)  # fmt: skip
        p.changeConstraint(gear, gearRatio=-1.0, maxForce=_GEAR_FORCE, physicsClientId=c)
        rotors.append(uid)
        geared.append((k, spec))
    if any(spec.dynamics.armature > LIGHT_GEAR * own_inertia(world, layout, p, c, k) for k, spec in geared):
        p.setPhysicsEngineParameter(numNonContactInnerIterations=ROTOR_SWEEPS, physicsClientId=c)
    return rotors


def own_inertia(world: CompiledWorld, layout: Layout, p: Any, c: int, k: int) -> float:
    """M_jj of joint ``k`` at the start: the mass (slider) or the moment about the axis (hinge) of everything the
    joint moves (its link and the links below it in PyBullet's tree), as the mass matrix's diagonal entry."""
    handle, spec = layout.joints[k], world.joints[k]
    below = {handle.link}
    for link in range(handle.link + 1, p.getNumJoints(handle.uid, physicsClientId=c)):  # parents come first
        if p.getJointInfo(handle.uid, link, physicsClientId=c)[16] in below:
            below.add(link)
    axis, anchor = np.asarray(spec.axis, float), np.asarray(spec.anchor, float)
    total = 0.0
    for i, body in enumerate(world.bodies):
        if layout.uid[i] != handle.uid or layout.link[i] not in below:
            continue
        if spec.kind is JointKind.SLIDER:
            total += body.mass
            continue
        turn = quat_matrices(body.quat)
        arm = np.asarray(body.pos, float) + turn @ np.asarray(body.com, float) - anchor
        across = arm - (arm @ axis) * axis
        total += float(axis @ turn @ body.inertia_tensor() @ turn.T @ axis) + body.mass * float(across @ across)
    return total


#: ERP of a mimic's gear (Bullet multiplies it by the solver's own, 0.2 for multibodies): the position error
#: left by the velocity-level solve is removed at the rate of a joint's own stops
_MIMIC_ERP = 1.0


def add_mimics(p: Any, c: int, world: CompiledWorld, layout: Layout) -> list[int]:
    """One gear constraint per coupling (URDF `<mimic>`, ``joint:mimic``), as pybullet's own mimic examples
    couple two joints: btMultiBodyGearConstraint holds ``rate_a + ratio * rate_b = 0``, and with an ERP (both
    joints in one multibody: Bullet reads the second joint's position from the first body) drives ``pos_a +
    ratio * pos_b`` to ``relativePositionTarget``. With a = the follower and b = the leader in PyBullet's
    coordinates (``sign`` x the world's), ratio = -multiplier x sign_a x sign_b and target = sign_a x offset."""
    index = {spec.name: k for k, spec in enumerate(world.joints)}
    gears = []
    for coupling in world.couplings:
        follower, leader = layout.joints[index[coupling.joint]], layout.joints[index[coupling.leader]]
        ratio, target = coupling.engine_terms(follower.sign, leader.sign)
        gear = p.createConstraint(follower.uid, follower.link, leader.uid, leader.link, p.JOINT_GEAR, [0.0, 1.0, 0.0],
                                  [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)  # fmt: skip
        one_body = follower.uid == leader.uid
        p.changeConstraint(gear, gearRatio=-ratio, maxForce=_GEAR_FORCE, erp=_MIMIC_ERP if one_body else 0.0,
                           relativePositionTarget=target, physicsClientId=c)  # fmt: skip
        gears.append(int(gear))
    return gears
