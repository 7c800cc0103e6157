"""Body frame <-> PyBullet's inertial frame, for bodies whose centre of mass or principal axes are offset.

PyBullet's base and link states (getBasePositionAndOrientation, getBaseVelocity, getLinkState's first,
second, seventh and eighth fields) and resetBasePositionAndOrientation are those of the *inertial* frame:
the centre of mass with the principal axes [checked: a base created at x = 1 with inertial frame
(0, 0, 0.5) reports z = 0.5; reset to (2, 0, 0) its box moves to z = -0.5]. The contract reports the body
frame, and the velocity of its origin: v_origin = v_com + omega x (origin - com).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry import quat_conj, quat_mul, quat_rotate
from ..types import CompiledWorld, Quat, Vec3
from ._build import has_offset


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _inertial_to_body(*row: Any) -> tuple[Any, ...]:
    """One state row (pos, quat x y z w, lin_vel, ang_vel) of an inertial frame -> of its body frame, given the
    COM (cx, cy, cz) and the conjugate of the principal axes' quaternion (jw, jx, jy, jz); the same code on
    plain floats (one body) and on numpy columns (every body at once): ``quat_mul``'s, ``quat_rotate``'s and the
    cross product's products written out in their order, so both give the same numbers, bit for bit."""
    px, py, pz, x, y, z, w, vx, vy, vz, ox, oy, oz, cx, cy, cz, jw, jx, jy, jz = row
    # qb = qc * conj(iq), qc = (w, x, y, z)
    bw = w * jw - x * jx - y * jy - z * jz
    bx = w * jx + x * jw + y * jz - z * jy
    by = w * jy - x * jz + y * jw + z * jx
    bz = w * jz + x * jy - y * jx + z * jw
    # arm = R(qb) com
    ux = by * cz - bz * cy
    uy = bz * cx - bx * cz
    uz = bx * cy - by * cx
    ax = cx + 2.0 * (bw * ux + by * uz - bz * uy)
    ay = cy + 2.0 * (bw * uy + bz * ux - bx * uz)
    az = cz + 2.0 * (bw * uz + bx * uy - by * ux)
    # drift = omega x (-arm)
    nx, ny, nz = -ax, -ay, -az
    return (px - ax, py - ay, pz - az, bx, by, bz, bw,
            vx + (oy * nz - oz * ny), vy + (oz * nx - ox * nz), vz + (ox * ny - oy * nx), ox, oy, oz)  # fmt: skip


#: up to this many offset bodies the conversion runs on plain floats (about 2.5 us per body); above, on
#: whole arrays (about 30 us whatever the count) [measured, in-process: 7 bodies 29 / 32 us, 12: 46 / 33]
PER_BODY_UP_TO = 8


class InertialFrames:
    """The bodies with an inertial offset, and the conversions of their states."""

    def __init__(self, world: CompiledWorld) -> None:
        self.offsets: dict[int, tuple[Vec3, Quat]] = {
            i: (b.com, b.inertia_quat) for i, b in enumerate(world.bodies) if has_offset(b)
        }
        #: per offset body: its COM in the body frame and the conjugate of its principal axes' quaternion
        self._conj = [(*com, *quat_conj(iq)) for com, iq in self.offsets.values()]
        self._rows = np.array(list(self.offsets), dtype=np.int64)
        #: the same, one row per quantity (cx, cy, cz, jw, jx, jy, jz), for the whole-array conversion
        self._columns = np.array(self._conj, dtype=float).reshape(-1, 7).T.copy()

    def to_body(self, arr: np.ndarray) -> None:
        """Rows of (pos, quat x y z w, lin_vel, ang_vel) of inertial frames -> of body frames, in place.

        Every step converts every offset body, so :func:`_inertial_to_body` runs on plain floats (the same
        operations in the same order as ``quat_mul`` and ``quat_rotate``: the same numbers), the rows read out
        and written back in one call each instead of tuples and numpy scalars."""
        if not self._conj:
            return
        if len(self._conj) > PER_BODY_UP_TO:
            self._to_body_columns(arr)
            return
        rows = arr[self._rows].tolist()
        for k, (conj, row) in enumerate(zip(self._conj, rows, strict=True)):
            rows[k] = list(_inertial_to_body(*row, *conj))
        arr[self._rows] = rows

    def _to_body_columns(self, arr: np.ndarray) -> None:
        """``to_body`` as whole-array operations on each quantity's column: the same operations in the same
        order, element by element (the same numbers, bit for bit: numpy's elementwise arithmetic rounds as
        Python's floats do), in about 45 numpy calls whatever the number of bodies."""
        arr[self._rows] = np.array(_inertial_to_body(*arr[self._rows].T, *self._columns)).T

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
