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

from ..types import CompiledWorld, JointKind
from ._build import Layout

#: a hinge rotor's mass and its moments across the axis: PyBullet needs positive ones; the joint holds them
_IDLE = 1e-9
#: the gear's force bound: the constraint, not a motor (far above any force a scenario produces)
_GEAR_FORCE = 1e12


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
    PyBullet's coordinate. Returns the rotors' body ids."""
    rotors = []
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
    return rotors
