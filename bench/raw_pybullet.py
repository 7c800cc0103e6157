"""The pile on PyBullet, written by hand with the adapter's settings (backends/pybullet, its settings()).

A bouncing surface's contact ERP is switched off for the substeps in which a bouncing pair is hit, by the
adapter's own function for that (``backends.pybullet._impacts``): it is the physics, not the runner's
overhead.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pybullet as p

from backends.pybullet._impacts import ImpactErp
from backends.pybullet._reads import base_rows
from backends.types import CompiledWorld, Motion, ShapeKind


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
        rows = []
        for uid in self.uids:
            pos, orn = p.getBasePositionAndOrientation(uid, physicsClientId=self.c)
            lin, ang = p.getBaseVelocity(uid, physicsClientId=self.c)
            rows.append(pos + (orn[3], orn[0], orn[1], orn[2]) + lin + ang)
        return np.array(rows, dtype=float)

    def close(self) -> None:
        p.disconnect(physicsClientId=self.c)


#: The loop bench/measure.py runs for this engine (found by the file name, bench/raw_<registry name>.py).
LOOP = PyBulletLoop
