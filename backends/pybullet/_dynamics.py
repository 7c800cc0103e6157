"""The parameters PyBullet takes after the build, body by body and joint by joint: no damping or sleeping, the
fitted surfaces, uncapped speeds, hull margins, start velocities, and the joints' motors, stops and rates."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import pybullet as p

from ..types import CompiledWorld, JointKind, Motion, ShapeKind
from ._build import Layout, initial_rate
from ._frames import InertialFrames
from ._surfaces import SurfaceFit

#: PyBullet clamps joint rates and free bases' speeds to 100 by default; ODE has no such limit.
MAX_JOINT_VELOCITY = 1e6
#: Collision margin of a body with convex hulls. PyBullet gives a hull built from vertices a 1 mm margin
#: that Bullet adds OUTSIDE the vertices (primitives keep theirs inside): a hull box rested 0.99 mm high
#: [checked]. Margin 0 rests at -1.0e-5 m but on 1 contact point (it rocks, as on GEOM_PLANE); 1e-4 keeps
#: 4 points and rests at +1.5e-5 m, the primitive box's -1.4e-5 m in size [checked, dt 0.01].
HULL_MARGIN = 1e-4


def set_body_dynamics(c: int, world: CompiledWorld, layout: Layout, fit: SurfaceFit, frames: InertialFrames) -> None:
    """Every body's damping (none), sleeping (never), surface, speed cap, hull margin and start velocity."""
    # PyBullet pitfall [checked]: a changeDynamics call on a link that also sets linearDamping,
    # angularDamping or activationState applies its other parameters to the base instead (and
    # drops joint limits). These three are per multibody anyway: set them alone, on the base.
    for uid in sorted(set(layout.uid)):
        for key, value in (
            ("linearDamping", 0.0),
            ("angularDamping", 0.0),
            ("activationState", p.ACTIVATION_STATE_DISABLE_SLEEPING),
        ):
            p.changeDynamics(uid, -1, physicsClientId=c, **{key: value})
    for i, spec in enumerate(world.bodies):
        uid, link = layout.uid[i], layout.link[i]
        extra: dict[str, Any] = {}
        if spec.motion is Motion.DYNAMIC:
            extra["localInertiaDiagonal"] = list(spec.inertia)
        p.changeDynamics(
            uid,
            link,
            restitution=fit.restitution[i],
            lateralFriction=fit.friction[i],
            physicsClientId=c,
            **extra,
        )
        # alone: combined with other parameters it misroutes them, like the damping. On a base it lifts
        # Bullet's 100 m/s cap on free bodies [checked: 2000 N for 0.04 s on 0.5 kg gave 100.0, now 160.0]
        p.changeDynamics(uid, link, maxJointVelocity=MAX_JOINT_VELOCITY, physicsClientId=c)
        if any(one.shape.kind is ShapeKind.CONVEX for one in spec.placed_shapes()):  # alone, as above
            p.changeDynamics(uid, link, collisionMargin=HULL_MARGIN, physicsClientId=c)
        if link < 0:  # the COM's velocity (the body's origin's, given, plus omega x arm)
            lin = frames.to_inertial(i, spec.pos, spec.quat, spec.lin_vel, spec.ang_vel)[2]
            p.resetBaseVelocity(uid, list(lin), list(spec.ang_vel), physicsClientId=c)


def set_joint_dynamics(
    c: int, world: CompiledWorld, layout: Layout, set_motor: Callable[[int, float, float], None]
) -> dict[int, float]:
    """Every joint's start: ball joints freed of PyBullet's default motor; each 1-dof joint's motor (through
    ``set_motor``), stops and start rate. Returns the 1-dof joints' start rates in PyBullet's sign."""
    rates: dict[int, float] = {}
    for k, joint in enumerate(world.joints):
        handle = layout.joints[k]
        if joint.kind is JointKind.BALL:  # PyBullet holds spherical links with a default motor
            p.setJointMotorControlMultiDof(
                handle.uid,
                handle.link,
                p.POSITION_CONTROL,
                targetPosition=[0.0, 0.0, 0.0, 1.0],
                force=[0.0, 0.0, 0.0],
                physicsClientId=c,
            )
        if handle.dofs != 1:
            continue
        motor = joint.motor
        set_motor(k, motor.vel if motor else 0.0, motor.fmax if motor else 0.0)
        if joint.lo is not None or joint.hi is not None:  # in its own call: never with damping
            lo = joint.lo if joint.lo is not None else -math.inf
            hi = joint.hi if joint.hi is not None else math.inf
            lo, hi = (lo, hi) if handle.sign > 0 else (-hi, -lo)
            p.changeDynamics(
                handle.uid,
                handle.link,
                jointLowerLimit=max(lo, -1e30),
                jointUpperLimit=min(hi, 1e30),
                physicsClientId=c,
            )
        rate = initial_rate(world, joint)
        rates[k] = handle.sign * rate
        if rate:  # a link's initial velocity is its joint rate (ball and fixed children inherit)
            p.resetJointState(handle.uid, handle.link, 0.0, handle.sign * rate, physicsClientId=c)
    return rates
