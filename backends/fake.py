"""A pure-Python test backend: exact ODE-style free motion, no contacts. For tests of the runner's logic.

Dynamic bodies move by semi-implicit Euler (v += (g + F/m) dt; x += v dt) with orientation integrated from
the angular velocity (no gyroscopic term); sliders to the environment carry a velocity motor bounded by
fmax; kinematic bodies follow the kit's track exactly. There are no contacts, so no collisions.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ._kit import KinematicPose, SubstepMean, substep_times
from .base import Backend
from .geometry import integrate_quat
from .types import (
    ALL_SHAPES,
    BodyStates,
    Capability,
    Contact,
    JointKind,
    JointStates,
    Motion,
    Precision,
    Quat,
    Vec3,
)


class FakeBackend(Backend):
    name = "fake"
    engine_distribution = "numpy"
    precision = Precision.FLOAT64
    capabilities: ClassVar[frozenset[Capability]] = ALL_SHAPES | {
        Capability.KINEMATIC,
        Capability.JOINT_SLIDER,
        Capability.JOINT_MOTOR,
        Capability.JOINT_LIMITS,
        Capability.SUBSTEPS,
        Capability.CONTACT_BOUNCE,  # vacuous: the fake backend has no contacts, so no surface changes anything
    }

    def _build(self) -> None:
        world = self.world
        n = len(world.bodies)
        self.pos = np.array([b.pos for b in world.bodies], float).reshape(n, 3)
        self.quat = np.array([b.quat for b in world.bodies], float).reshape(n, 4)
        self.vel = np.array([b.lin_vel for b in world.bodies], float).reshape(n, 3)
        self.ang = np.array([b.ang_vel for b in world.bodies], float).reshape(n, 3)
        self.mass = np.array([b.mass for b in world.bodies], float)
        self.inertia = np.array([b.inertia for b in world.bodies], float).reshape(n, 3)
        self.moves = np.array([b.motion is Motion.DYNAMIC for b in world.bodies])
        index = {b.name: i for i, b in enumerate(world.bodies)}
        self.sliders = [(index[j.body], np.asarray(j.axis), j) for j in world.joints if j.kind is JointKind.SLIDER]
        self.start = {i: self.pos[i].copy() for i, _, _ in self.sliders}
        self.motor = {j.name: (j.motor.vel, j.motor.fmax) if j.motor else (0.0, 0.0) for _, _, j in self.sliders}
        self.applied = SubstepMean(len(world.joints))

    def _step(self) -> None:
        n = self.world.substeps
        h = self.world.dt / n
        g = np.asarray(self.world.gravity)
        force = np.zeros((len(self.world.bodies), 6))
        for i, acc in self.forces.items():
            force[i] = acc
        self.applied.start()
        for t in substep_times(self.world.dt, n):
            for d in np.flatnonzero(self.moves):
                self.vel[d] += (g + force[d, :3] / self.mass[d]) * h
                self.ang[d] += force[d, 3:] / self.inertia[d].mean() * h
            applied = np.zeros(len(self.world.joints))
            for k, (i, axis, joint) in enumerate(self.sliders):
                vel, fmax = self.motor[joint.name]
                along = float(self.vel[i] @ axis)
                # the joint removes all motion off its axis; the motor changes the rate within fmax*h/m
                self.vel[i] = along * axis
                self.ang[i] = 0.0
                dv = np.clip(vel - along, -fmax * h / self.mass[i], fmax * h / self.mass[i]) if fmax > 0 else 0.0
                self.vel[i] += dv * axis
                applied[k] = dv * self.mass[i] / h
            self.applied.add(applied)
            for d in np.flatnonzero(self.moves):
                self.pos[d] += self.vel[d] * h
                self.quat[d] = integrate_quat(self.quat[d], self.ang[d], h)
            for i, pose in self.kinematic.items():
                self.pos[i], self.quat[i] = pose.at(t)
        self.applied.finish()

    def _body_states(self) -> BodyStates:
        return BodyStates(self.pos.copy(), self.quat.copy(), self.vel.copy(), self.ang.copy())

    def _joint_states(self) -> JointStates:
        m = len(self.world.joints)
        position, velocity = np.full(m, np.nan), np.full(m, np.nan)
        for k, (i, axis, _) in enumerate(self.sliders):
            position[k] = float((self.pos[i] - self.start[i]) @ axis)
            velocity[k] = float(self.vel[i] @ axis)
        return JointStates(position, velocity, self.applied.mean.copy())

    def _contacts(self) -> list[Contact]:
        return []

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self.pos[body], self.quat[body] = pose.pos, pose.quat
        self.vel[body], self.ang[body] = pose.lin_vel, pose.ang_vel

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        self.motor[self.world.joints[joint].name] = (vel, fmax)

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self.pos[body], self.quat[body], self.vel[body], self.ang[body] = pos, quat, lin_vel, ang_vel
