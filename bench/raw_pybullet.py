"""The pile on PyBullet, written by hand with the adapter's settings (backends/pybullet, its settings()).

A bouncing surface's contact ERP is switched off for the substeps in which a bouncing pair is hit, by the
adapter's own function for that (``backends.pybullet._impacts``): it is the physics, not the runner's
overhead.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from itertools import chain, repeat
from typing import Any

import numpy as np
import pybullet as p

from backends.pybullet._impacts import ImpactErp
from backends.pybullet._reads import base_rows
from backends.types import CompiledWorld, Motion, ShapeKind

from .raw_common import Servo, servo_rates

_flat = chain.from_iterable

#: PyBullet's row (pos, quaternion x y z w, lin, ang) in the loops' order (quaternion w x y z).
_WXYZ_ROW = np.array([0, 1, 2, 6, 3, 4, 5, 7, 8, 9, 10, 11, 12])


class PyBulletLoop:
    def __init__(self, world: CompiledWorld, s: Mapping[str, Any]) -> None:
        self.c = c = p.connect(p.DIRECT)
        h = s["fixed_time_step"]
        p.setGravity(*world.gravity, physicsClientId=c)
        p.setTimeStep(h, physicsClientId=c)
        half_plane = 1000.0  # the adapter's plane: a box whose top face is the plane (its settings' "plane")
        self.uids = []
        for b in world.bodies:
            if b.shape.kind is ShapeKind.PLANE:
                shape = p.createCollisionShape(
                    p.GEOM_BOX,
                    halfExtents=[half_plane] * 3,
                    collisionFramePosition=[0, 0, -half_plane],
                    physicsClientId=c,
                )
            else:
                shape = p.createCollisionShape(
                    p.GEOM_BOX,
                    halfExtents=[x / 2 for x in b.shape.size],
                    collisionFramePosition=[0, 0, 0],
                    physicsClientId=c,
                )
            q = b.quat
            self.uids.append(
                p.createMultiBody(
                    baseMass=b.mass if b.motion is Motion.DYNAMIC else 0.0,
                    baseCollisionShapeIndex=shape,
                    basePosition=list(b.pos),
                    baseOrientation=[q[1], q[2], q[3], q[0]],
                    physicsClientId=c,
                )
            )
        p.setPhysicsEngineParameter(
            fixedTimeStep=h,
            numSubSteps=s["num_sub_steps"],
            numSolverIterations=s["solver_iterations"],
            restitutionVelocityThreshold=s["restitution_velocity_threshold"],
            contactBreakingThreshold=s["contact_breaking_threshold"],
            deterministicOverlappingPairs=int(s["deterministic_overlapping_pairs"]),
            physicsClientId=c,
        )
        surface = world.default_surface
        restitution = math.sqrt(surface.bounce)  # settings' surface_mapping "sqrt": c_a * c_b = value
        friction = math.sqrt(min(surface.mu, s["friction_clamp"]))
        for uid in self.uids:
            p.changeDynamics(uid, -1, linearDamping=0.0, physicsClientId=c)
            p.changeDynamics(uid, -1, angularDamping=0.0, physicsClientId=c)
            p.changeDynamics(uid, -1, activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=c)
        for uid, b in zip(self.uids, world.bodies, strict=True):
            extra = {"localInertiaDiagonal": list(b.inertia)} if b.motion is Motion.DYNAMIC else {}
            p.changeDynamics(uid, -1, restitution=restitution, lateralFriction=friction, physicsClientId=c, **extra)
            p.resetBaseVelocity(uid, list(b.lin_vel), list(b.ang_vel), physicsClientId=c)
        lut = [[-1] for _ in range(max(self.uids) + 1)]  # (multibody, link + 1) -> body index
        for i, uid in enumerate(self.uids):
            lut[uid][0] = i
        kick = math.hypot(*world.gravity) * h
        rest = [restitution] * len(self.uids)
        self.impacts = ImpactErp(c, lut, rest, s["restitution_velocity_threshold"], kick)

    def step(self) -> None:
        if self.impacts.active:
            self.impacts.before_substep(lambda: base_rows(self.c, self.uids))
        p.stepSimulation(physicsClientId=self.c)

    def read(self) -> np.ndarray:
        """Two calls per base (PyBullet has no state getter for several multibodies), the floats streamed
        into one array."""
        c, n = self.c, len(self.uids)
        poses = map(p.getBasePositionAndOrientation, self.uids, repeat(c))
        twists = map(p.getBaseVelocity, self.uids, repeat(c))
        flat = chain.from_iterable(chain.from_iterable(chain.from_iterable(zip(poses, twists, strict=True))))
        return np.fromiter(flat, np.float64, 13 * n).reshape(n, 13)[:, _WXYZ_ROW]

    def close(self) -> None:
        p.disconnect(physicsClientId=self.c)


#: The loop bench/measure.py runs for this engine (found by the file name, bench/raw_<registry name>.py).
LOOP = PyBulletLoop


class PyBulletRobotLoop:
    """A robot on PyBullet by hand (bench/robot.py): the servos' rates in one ``setJointMotorControlArray``
    per multibody, ``stepSimulation``, then ``getBasePositionAndOrientation`` + ``getBaseVelocity`` per
    moving base (an unturned static base, the ground or a fixed robot's, is read once, as the adapter reads
    it), one ``getLinkStates`` (with velocities) per multibody and one ``getJointStates`` per multibody
    (position, velocity and the motor's applied torque), the floats streamed into arrays."""

    def __init__(self, adapter: Any, servos: list[Servo]) -> None:
        if adapter.world.substeps != 1 or adapter._impacts.active:
            raise ValueError("the hand-written robot loop steps once per step with no bouncing pair")
        self.c, lay = adapter._c, adapter._layout
        self.servos = servos
        self.n = len(adapter.world.bodies)
        self.bases, self.base_rows = adapter._moving_uids, adapter._moving_rows
        self.still = np.zeros((self.n, 13))
        self.still[adapter._static] = base_rows(self.c, [lay.uid[i] for i in adapter._static])
        self.groups = [(uid, list(links), list(bodies)) for uid, links, bodies in lay.link_groups]
        handles = [lay.joints[s.joint] for s in servos]
        self.sign = [h.sign for h in handles]
        #: per multibody: its servoed links and their places in ``servos``
        self.motors = [(u, [h.link for h in handles if h.uid == u], [k for k, h in enumerate(handles) if h.uid == u])
                       for u in sorted({h.uid for h in handles})]  # fmt: skip
        moving = [k for k, h in enumerate(lay.joints) if h.dofs == 1]  # world joints with a coordinate
        uids = sorted({lay.joints[k].uid for k in moving})
        self.joint_groups = [(u, [lay.joints[k].link for k in moving if lay.joints[k].uid == u]) for u in uids]
        order = [k for u in uids for k in moving if lay.joints[k].uid == u]  # read order -> world joint
        self.joint_order, self.joint_sign = np.array(order), np.array([lay.joints[k].sign for k in order])
        self.servo_row = [order.index(s.joint) for s in servos]
        #: PyBullet reads a joint from the pose the robot was built in, its start: the model's zero is back by
        #: the start position (the runner's coordinate, runner.compile.world.joint_zeros)
        self.zero = [s.zero for s in servos]
        self.joint_zero = np.zeros(len(order))
        for s, row in zip(servos, self.servo_row, strict=True):
            self.joint_zero[row] = s.zero
        self.read()

    def step(self, targets: list[float]) -> None:
        c, rates = self.c, servo_rates(self.servos, targets, self.q)
        for uid, links, k in self.motors:
            p.setJointMotorControlArray(
                uid, links, p.VELOCITY_CONTROL, targetVelocities=[self.sign[i] * rates[i] for i in k],
                forces=[self.servos[i].fmax for i in k], physicsClientId=c,
            )  # fmt: skip
        p.stepSimulation(physicsClientId=c)

    def read(self) -> None:
        c = self.c
        rows = self.still.copy()
        if self.bases:
            rows[self.base_rows] = base_rows(c, self.bases)
        for uid, links, bodies in self.groups:
            states = p.getLinkStates(uid, links, computeLinkVelocity=1, computeForwardKinematics=1, physicsClientId=c)
            rows[bodies] = np.fromiter(_flat(_flat((s[0], s[1], s[6], s[7]) for s in states)), np.float64,
                                       13 * len(links)).reshape(-1, 13)  # fmt: skip
        states = []
        for uid, links in self.joint_groups:
            states.extend(p.getJointStates(uid, links, physicsClientId=c))
        joints = np.fromiter(_flat((j[0], j[1], j[3]) for j in states), np.float64, 3 * len(states)).reshape(-1, 3)
        self.rows, self.joints = rows, joints
        q = joints[:, 0]
        self.q = [self.sign[i] * float(q[r]) + self.zero[i] for i, r in enumerate(self.servo_row)]

    def joint_positions(self) -> dict[int, float]:
        """World joint index -> its position (the runner's coordinate) after the last read."""
        q = self.joint_sign * self.joints[:, 0] + self.joint_zero
        return dict(zip(self.joint_order.tolist(), q.tolist(), strict=True))


#: bench/robot.py's hand-written robot loop for this engine (built from the adapter's world).
ROBOT_LOOP = PyBulletRobotLoop
