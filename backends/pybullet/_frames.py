"""Body frame <-> PyBullet's inertial frame, for bodies whose centre of mass or principal axes are offset.

PyBullet's base and link states (getBasePositionAndOrientation, getBaseVelocity, getLinkState's first,
second, seventh and eighth fields) and resetBasePositionAndOrientation are those of the *inertial* frame:
the centre of mass with the principal axes [checked: a base created at x = 1 with inertial frame
(0, 0, 0.5) reports z = 0.5; reset to (2, 0, 0) its box moves to z = -0.5]. The contract reports the body
frame, and the velocity of its origin: v_origin = v_com + omega x (origin - com).
"""

from __future__ import annotations

import numpy as np

from ..geometry import quat_conj, quat_mul, quat_rotate
from ..types import CompiledWorld, Quat, Vec3
from ._build import has_offset


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


class InertialFrames:
    """The bodies with an inertial offset, and the conversions of their states."""

    def __init__(self, world: CompiledWorld) -> None:
        self.offsets: dict[int, tuple[Vec3, Quat]] = {
            i: (b.com, b.inertia_quat) for i, b in enumerate(world.bodies) if has_offset(b)
        }

    def to_body(self, arr: np.ndarray) -> None:
        """Rows of (pos, quat x y z w, lin_vel, ang_vel) of inertial frames -> of body frames, in place."""
        for i, (com, iq) in self.offsets.items():
            row = arr[i]
            qc = (row[6], row[3], row[4], row[5])
            qb = quat_mul(qc, quat_conj(iq))
            arm = quat_rotate(qb, com)  # origin -> COM, world frame
            omega = (row[10], row[11], row[12])
            drift = _cross(omega, (-arm[0], -arm[1], -arm[2]))
            row[0:3] = [row[0] - arm[0], row[1] - arm[1], row[2] - arm[2]]
            row[3:7] = [qb[1], qb[2], qb[3], qb[0]]
            row[7:10] = [row[7] + drift[0], row[8] + drift[1], row[9] + drift[2]]

    def to_inertial(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> tuple[Vec3, Quat, Vec3]:
        """A body-frame pose and origin velocity -> the inertial frame's pose and the COM's velocity."""
        if body not in self.offsets:
            return pos, quat, lin_vel
        com, iq = self.offsets[body]
        arm = quat_rotate(quat, com)
        drift = _cross(ang_vel, arm)
        return (
            (pos[0] + arm[0], pos[1] + arm[1], pos[2] + arm[2]),
            quat_mul(quat, iq),
            (lin_vel[0] + drift[0], lin_vel[1] + drift[1], lin_vel[2] + drift[2]),
        )
