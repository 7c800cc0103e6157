"""Free rigid bodies in numpy, with ODE's conventions: semi-implicit Euler on the linear and angular momentum
equations (v += (g + F/m) h, w += I_world^-1 (tau - w x I_world w) h, then x += v h and the orientation turned
by w h), sliders to the environment with a velocity motor bounded by fmax and hard stops, kinematic bodies
following the kit's track. Boxes, spheres and static planes; no contacts (the capability ``world:contacts``
is not declared, so the contract suite's contact tests are skipped with that reason)."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from backends._kit import KinematicPose, SubstepMean, substep_times
from backends.base import Backend
from backends.geometry import integrate_quat
from backends.types import (
    BodyStates,
    Capability,
    Contact,
    JointStates,
    Motion,
    Precision,
    Quat,
    Vec3,
)


class OutsideEngineError(ArithmeticError):
    """The engine's own failure: a state that is no longer finite."""


def _rotation(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


class OutsideBackend(Backend):
    name = "outside"
    engine_distribution = "scenario-outside-engine"
    precision = Precision.FLOAT64
    capabilities: ClassVar[frozenset[Capability]] = frozenset(
        {
            Capability.SHAPE_BOX,
            Capability.SHAPE_SPHERE,
            Capability.SHAPE_PLANE,
            Capability.KINEMATIC,
            Capability.JOINT_SLIDER,
            Capability.JOINT_MOTOR,
            Capability.JOINT_LIMITS,
            Capability.SUBSTEPS,
        }
    )
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = (OutsideEngineError,)

    def _build(self) -> None:
        bodies = self.world.bodies
        n = len(bodies)
        self.pos = np.array([b.pos for b in bodies], float).reshape(n, 3)
        self.quat = np.array([b.quat for b in bodies], float).reshape(n, 4)
        self.vel = np.array([b.lin_vel for b in bodies], float).reshape(n, 3)
        self.ang = np.array([b.ang_vel for b in bodies], float).reshape(n, 3)
        self.mass = np.array([b.mass for b in bodies], float)
        self.inertia = np.array([b.inertia for b in bodies], float).reshape(n, 3)  # principal, body frame
        self.dynamic = [i for i, b in enumerate(bodies) if b.motion is Motion.DYNAMIC]
        index = {b.name: i for i, b in enumerate(bodies)}
        self.sliders = [(index[j.body], np.asarray(j.axis, float), j) for j in self.world.joints]
        self.start = {i: self.pos[i].copy() for i, _, _ in self.sliders}
        self.motor = [(j.motor.vel, j.motor.fmax) if j.motor else (0.0, 0.0) for _, _, j in self.sliders]
        self.motor_force = SubstepMean(len(self.sliders))

    def _angular_step(self, i: int, torque: np.ndarray, h: float) -> None:
        r = _rotation(self.quat[i])
        inertia = r @ np.diag(self.inertia[i]) @ r.T
        w = self.ang[i]
        self.ang[i] = w + np.linalg.solve(inertia, torque - np.cross(w, inertia @ w)) * h

    def _slider_step(self, k: int, h: float) -> float:
        """Keep the body on its axis, then let the motor change its rate by at most fmax*h/m: the force used."""
        i, axis, _ = self.sliders[k]
        along = float(self.vel[i] @ axis)
        self.vel[i], self.ang[i] = along * axis, 0.0
        vel, fmax = self.motor[k]
        limit = fmax * h / self.mass[i]
        dv = float(np.clip(vel - along, -limit, limit))
        self.vel[i] += dv * axis
        return dv * self.mass[i] / h

    def _stop(self, k: int) -> None:
        """A hard stop: the coordinate put back on its limit and the rate into it removed."""
        i, axis, joint = self.sliders[k]
        x = float((self.pos[i] - self.start[i]) @ axis)
        v = float(self.vel[i] @ axis)
        if joint.hi is not None and x > joint.hi:
            self.pos[i] -= (x - joint.hi) * axis
            self.vel[i] -= max(v, 0.0) * axis
        elif joint.lo is not None and x < joint.lo:
            self.pos[i] += (joint.lo - x) * axis
            self.vel[i] -= min(v, 0.0) * axis

    def _step(self) -> None:
        n = self.world.substeps
        h = self.world.dt / n
        g = np.asarray(self.world.gravity, float)
        wrench = np.zeros((len(self.world.bodies), 6))
        for i, acc in self.forces.items():
            wrench[i] = acc
        self.motor_force.start()
        for t in substep_times(self.world.dt, n):
            for i in self.dynamic:
                self.vel[i] += (g + wrench[i, :3] / self.mass[i]) * h
                self._angular_step(i, wrench[i, 3:], h)
            self.motor_force.add(np.array([self._slider_step(k, h) for k in range(len(self.sliders))]))
            for i in self.dynamic:
                self.pos[i] += self.vel[i] * h
                self.quat[i] = integrate_quat(self.quat[i], self.ang[i], h)
            for k in range(len(self.sliders)):
                self._stop(k)
            for i, pose in self.kinematic.items():
                self.pos[i], self.quat[i] = pose.at(t)
        self.motor_force.finish()
        if not (np.all(np.isfinite(self.pos)) and np.all(np.isfinite(self.vel)) and np.all(np.isfinite(self.ang))):
            raise OutsideEngineError("the state is no longer finite")

    def _body_states(self) -> BodyStates:
        return BodyStates(self.pos.copy(), self.quat.copy(), self.vel.copy(), self.ang.copy())

    def _joint_states(self) -> JointStates:
        m = len(self.sliders)
        position, velocity = np.zeros(m), np.zeros(m)
        for k, (i, axis, _) in enumerate(self.sliders):
            position[k] = float((self.pos[i] - self.start[i]) @ axis)
            velocity[k] = float(self.vel[i] @ axis)
        return JointStates(position, velocity, self.motor_force.mean.copy())

    def _contacts(self) -> list[Contact]:
        return []

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self.pos[body], self.quat[body] = pose.pos, pose.quat
        self.vel[body], self.ang[body] = pose.lin_vel, pose.ang_vel

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        self.motor[joint] = (vel, fmax)

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self.pos[body], self.quat[body], self.vel[body], self.ang[body] = pos, quat, lin_vel, ang_vel
