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
