"""The pile on DART, written by hand with the adapter's settings (backends/dart, its settings()).

One skeleton per body in world order (a WeldJoint for the plane, a FreeJoint per box), the ODE
collision detector, no deactivation, per-shape friction and restitution as the adapter reports them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import dartpy as dart
import numpy as np

from backends.dart._reads import state_readers
from backends.types import CompiledWorld, Motion, ShapeKind

_DETECTORS = {
    "ode": dart.collision.OdeCollisionDetector,
    "fcl": dart.collision.FCLCollisionDetector,
    "bullet": dart.collision.BulletCollisionDetector,
    "dart": dart.collision.DARTCollisionDetector,
}


def _isometry(pos: Any, quat: Any) -> Any:
    t = dart.math.Isometry3()
    t.set_identity()
    t.set_quaternion(dart.math.Quaternion(*(float(x) for x in quat)))
    t.set_translation(np.asarray(pos, dtype=float))
    return t


class DartLoop:
    def __init__(self, world: CompiledWorld, s: Mapping[str, Any]) -> None:
        if s["engine_steps_per_step"] != 1 or s["surfaces"] != "fixed per shape":
            raise ValueError(f"unexpected DART settings: {dict(s)}")
        self.w = w = dart.simulation.World(world.name)
        w.setGravity(np.asarray(world.gravity, dtype=float))
        w.setTimeStep(s["engine_dt"])
        sleep = w.getDeactivationOptions()
        sleep.mEnabled = bool(s["deactivation"])
        w.setDeactivationOptions(sleep)
        w.getConstraintSolver().setCollisionDetector(_DETECTORS[s["collision_detector"]]())
        self.skeletons = []
        for i, b in enumerate(world.bodies):
            skeleton = dart.dynamics.Skeleton(f"{i}:{b.name}")
            if b.motion is Motion.STATIC:
                joint, node = skeleton.createWeldJointAndBodyNodePair()
                joint.setTransformFromParentBodyNode(_isometry(b.pos, b.quat))
            else:
                joint, node = skeleton.createFreeJointAndBodyNodePair()
            node.setName(b.name)
            if b.shape.kind is ShapeKind.PLANE:
                shape = dart.dynamics.PlaneShape(np.array([0.0, 0.0, 1.0]), 0.0)
            else:
                shape = dart.dynamics.BoxShape(np.asarray(b.shape.size, dtype=float))
            shape_node = node.createShapeNode(shape, f"{i}")
            shape_node.createCollisionAspect()
            aspect = shape_node.createDynamicsAspect()
            aspect.setFrictionCoeff(s["friction_per_body"][b.name])
            aspect.setRestitutionCoeff(s["restitution_per_body"][b.name])
            if b.mass > 0.0:  # DART's own moments when they equal the world's (as the adapter does)
                moments = shape.computeInertia(b.mass)
                if not np.allclose(np.diag(moments), b.inertia, rtol=1e-9, atol=0.0):
                    moments = np.diag(np.asarray(b.inertia, float))
                node.setInertia(dart.dynamics.Inertia(b.mass, np.zeros(3), moments))
            if b.motion is Motion.DYNAMIC:
                joint.setPositions(dart.dynamics.FreeJoint.convertToPositions(_isometry(b.pos, b.quat)))
                joint.setVelocities(np.concatenate([np.asarray(b.ang_vel, float), np.asarray(b.lin_vel, float)]))
            self.skeletons.append(skeleton)
        for skeleton in self.skeletons:
            w.addSkeleton(skeleton)
        self.free_at = np.array([i for i, b in enumerate(world.bodies) if b.motion is not Motion.STATIC], dtype=int)
        self.free = [self.skeletons[i] for i in self.free_at]
        self.read_q, self.read_v = state_readers(self.free)  # two skeletons per call (a Chain of their roots)
        self.fixed_rows = np.zeros((len(world.bodies), 13))
        self.fixed_rows[:, :7] = [list(b.pos) + list(b.quat) for b in world.bodies]

    def step(self) -> None:
        self.w.step()

    def read(self) -> np.ndarray:
        """The cheapest read dartpy 6.20 offers: getPositions and getVelocities of a Chain between two free
        skeletons' roots, two skeletons per call (DART has no world-level state getter; the adapter's
        ``backends.dart._reads``), the rotation vectors turned into quaternions on arrays."""
        rows = self.fixed_rows.copy()
        if self.free:
            q = np.concatenate([read() for read in self.read_q]).reshape(-1, 6)
            v = np.concatenate([read() for read in self.read_v]).reshape(-1, 6)
            angle = np.sqrt((q[:, :3] ** 2).sum(axis=1))
            small = angle < 1e-12
            scale = np.sin(angle / 2) / np.where(small, 1.0, angle)
            scale[small] = 0.5  # sin(a/2)/a -> 1/2
            free = self.free_at
            rows[free, :3] = q[:, 3:]
            rows[free, 3] = np.cos(angle / 2)
            rows[free, 4:7] = q[:, :3] * scale[:, None]
            rows[free, 7:10], rows[free, 10:13] = v[:, 3:], v[:, :3]
        return rows

    def close(self) -> None:
        self.w.removeAllSkeletons()


#: The loop bench/measure.py runs for this engine (found by the file name, bench/raw_<registry name>.py).
LOOP = DartLoop
