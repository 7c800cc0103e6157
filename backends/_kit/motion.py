"""Inputs every adapter keeps between the runner's calls and its engine's step, written once.

* :class:`KinematicTrack`: each kinematic body's commanded motion (the pose it starts the step from and
  its velocity), the pose it must have at any time into the step, and the pose it ends at.
* :class:`OneStepForces`: forces and torques added for the next step only (ODE's ``dBodyAddForce``).
* :class:`SubstepMean`: the mean of a per-substep quantity (motor forces) over one scenario step.
* :func:`substep_times`: the times into a step at which its substeps end.

Every adapter computes a pose into the step as ``pos + lin_vel*t`` and ``integrate_quat(quat, ang_vel,
t)``, so all of them put a kinematic body at the same doubles.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import NamedTuple

import numpy as np

from ..geometry import integrate_quat
from ..types import CompiledWorld, Motion, Quat, Vec3


class KinematicPose(NamedTuple):
    """Where a kinematic body starts the coming step and the velocity it moves with (world frame)."""

    pos: Vec3
    quat: Quat  # w, x, y, z
    lin_vel: Vec3
    ang_vel: Vec3

    def at(self, t: float) -> tuple[Vec3, Quat]:
        """The pose ``t`` seconds into the step: moved by the linear velocity, turned by the angular one."""
        p, v = self.pos, self.lin_vel
        return (p[0] + v[0] * t, p[1] + v[1] * t, p[2] + v[2] * t), integrate_quat(self.quat, self.ang_vel, t)


def _vec(values: Sequence[float]) -> tuple[float, float, float]:
    return (float(values[0]), float(values[1]), float(values[2]))


class KinematicTrack:
    """The commanded motion of every kinematic body of a world (initially its pose and velocity)."""

    def __init__(self, world: CompiledWorld) -> None:
        self._poses: dict[int, KinematicPose] = {
            i: KinematicPose(b.pos, b.quat, b.lin_vel, b.ang_vel)
            for i, b in enumerate(world.bodies)
            if b.motion is Motion.KINEMATIC
        }

    def __bool__(self) -> bool:
        return bool(self._poses)

    def __contains__(self, body: object) -> bool:
        return body in self._poses

    def __getitem__(self, body: int) -> KinematicPose:
        return self._poses[body]

    def items(self) -> Iterator[tuple[int, KinematicPose]]:
        return iter(self._poses.items())

    def set(self, body: int, pos: Sequence[float], quat: Sequence[float], lin: Sequence[float],
            ang: Sequence[float]) -> KinematicPose:  # fmt: skip
        q = (float(quat[0]), float(quat[1]), float(quat[2]), float(quat[3]))
        pose = self._poses[body] = KinematicPose(_vec(pos), q, _vec(lin), _vec(ang))
        return pose

    def advance(self, dt: float) -> None:
        """The step is over: each body starts the next one where its velocity took it, with that velocity
        (a kinematic body not set again keeps moving)."""
        for i, pose in self._poses.items():
            pos, quat = pose.at(dt)
            self._poses[i] = KinematicPose(pos, quat, pose.lin_vel, pose.ang_vel)


class OneStepForces:
    """Forces and torques (world frame, at the centre of mass) accumulated for the next step only."""

    def __init__(self) -> None:
        self._acc: dict[int, np.ndarray] = {}  # body -> (fx, fy, fz, tx, ty, tz), in the order first pushed

    def __bool__(self) -> bool:
        return bool(self._acc)

    def add(self, body: int, force: Sequence[float], torque: Sequence[float]) -> None:
        acc = self._acc.get(body)
        if acc is None:
            acc = self._acc[body] = np.zeros(6)
        acc[:3] += force
        acc[3:] += torque

    def items(self) -> Iterator[tuple[int, np.ndarray]]:
        return iter(self._acc.items())

    def clear(self) -> None:
        self._acc.clear()


class SubstepMean:
    """The mean over a scenario step of a vector measured once per engine step (summed from zero).

    Each step's sum is a fresh array, begun as 0 + its first value (a -0.0 reads +0.0, as a sum from zero
    does), and a step of one engine step takes that sum as its mean (x / 1 is x): the same numbers as
    zeroing, adding and dividing, with one whole-array operation instead of three."""

    def __init__(self, size: int) -> None:
        self._total = np.zeros(size)
        self._count = 0
        self._mean = np.zeros(size)

    def start(self) -> None:
        self._count = 0

    def add(self, values: np.ndarray | Sequence[float]) -> None:
        if self._count:
            self._total += values
        else:
            self._total = np.add(values, 0.0)
        self._count += 1

    def finish(self) -> np.ndarray:
        """Closes the step; its mean stays available as :attr:`mean` until the next one finishes."""
        if self._count == 1:
            self._mean = self._total
        elif self._count:
            self._mean = self._total / self._count
        return self._mean

    @property
    def mean(self) -> np.ndarray:
        return self._mean


def substep_times(dt: float, n: int) -> list[float]:
    """When each of the ``n`` substeps of a step of ``dt`` ends, from the step's start (the last: ``dt``)."""
    return [dt * (s / n) for s in range(1, n)] + [dt]
