"""Joint armature on DART: the armature added to the joint's entry of DART's implicit joint inertia.

MuJoCo's armature ``a`` adds ``a`` to the joint's diagonal entry of the mass matrix and nothing else. DART 6.20
has no armature parameter (GenericJoint's properties: limits, spring, rest position, damping, Coulomb friction),
but it integrates joint damping implicitly: its articulated-body pass adds ``h * damping`` (and ``h^2 *
stiffness``) to the joint's projected articulated inertia ``S^T I^A S`` (GenericJoint's implicit inverse
projected inertia, used for the accelerations and passed on to the parent), and applies the damping force
``-damping * qdot`` with the rate at the start of the step. In Featherstone's algorithm armature is exactly an
addition to that same scalar. So a joint with armature gets the damping coefficient ``c + a / h`` (``c`` its own
damping, ``h`` the engine step) and, before every engine step, the generalized force ``+(a / h) qdot`` from the
same rate: the force terms cancel to the last bit and the inertia gains ``a``. The force is applied as an
equal and opposite pair on the joint's two bodies (a torque about the hinge's axis; a force along the slider's
axis at the child's origin), which is that generalized force on the joint and none on any other coordinate:
DART reads a joint's own force (``setForce``) only with the FORCE actuator, while the adapter's joints are
PASSIVE or SERVO (the motor). Measured: a hinge of I = 0.05
kg m^2 with a = 0.03 under 0.2 N m spins up at tau / (I + a) = 2.5 rad/s^2 to 4e-14 (tests/sim/test_joint_dynamics.py).

What it does not reach: DART's constraint impulses (contacts, stops, the servo that realises motors and
friction loss) use the explicit projected inertia, without the implicit terms, so an impulse on the joint's
coordinate sees the joint without its armature, as it sees it without its damping's implicit term. Contacts and
stops are re-sized through the armature after each step (_impacts); the servo, whose impulse sits at its bound,
is refused with armature (:func:`check_armature`; docs/backends/dart.md, "Joint dynamics").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, JointKind


def add_armature(joints: list[Any], h: float) -> list[tuple[Any, float, bool]]:
    """Raise the damping of each slider and hinge with armature by ``a / h``; returns (DART joint, a / h,
    hinge) for :func:`hold_armature`. ``joints``: the built JointHandles (``spec``, ``joint``)."""
    held = []
    for handle in joints:
        armature = handle.spec.dynamics.armature
        if armature <= 0.0 or handle.spec.kind not in (JointKind.HINGE, JointKind.SLIDER):
            continue
        extra = armature / h
        handle.joint.setDampingCoefficient(0, handle.spec.dynamics.damping + extra)
        held.append((handle.joint, extra, handle.spec.kind is JointKind.HINGE))
    return held


def hold_armature(held: list[tuple[Any, float, bool]]) -> None:
    """Before an engine step (World.step clears external forces): the pair cancelling the armature's damping
    force, from the rate at the step's start as DART's damping takes it."""
    for joint, extra, hinge in held:
        child, parent = joint.getChildBodyNode(), joint.getParentBodyNode()
        frame = child.getWorldTransform()
        axis = np.asarray(frame.rotation()) @ np.asarray(joint.getTransformFromChildBodyNode().rotation()) @ np.asarray(
            joint.getAxis(), dtype=float
        )
        push = extra * joint.getVelocity(0) * axis
        if hinge:
            child.addExtTorque(push)
            if parent is not None:
                parent.addExtTorque(-push)
            continue
        child.addExtForce(push, np.zeros(3), False, True)
        if parent is not None:  # at the same world point: the pair does no work on any other motion
            at = parent.getWorldTransform().inverse().multiply(frame.translation())
            parent.addExtForce(-push, np.asarray(at, dtype=float), False, True)


def check_armature(world: CompiledWorld) -> None:
    """Refuse a joint with armature that a motor drives (a motor, servo, velocity drive or motor action) or
    that has friction loss (the runner's bounded motor): DART's servo constraint, which realises them,
    computes its impulse without the armature, so a bounded motor would accelerate the joint at fmax / I
    instead of fmax / (I + a) (measured: 12.5 rad/s^2 instead of 5 on a 0.04 kg m^2 wheel with a = 0.06)."""
    for spec in world.joints:
        if spec.dynamics.armature > 0.0 and (spec.motor is not None or spec.dynamics.frictionloss > 0.0):
            what = "a motor" if spec.motor is not None else "friction loss"
            raise UnsupportedFeature(
                f"Backend `dart` cannot run joint `{spec.name}`: armature with {what} (DART's servo constraint, "
                "which realises motors and friction loss, does not see the armature; docs/backends/dart.md)"
            )
