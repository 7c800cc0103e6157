"""Body frame <-> PyBullet's inertial frame, for bodies whose centre of mass or principal axes are offset.

PyBullet's base and link states (getBasePositionAndOrientation, getBaseVelocity, getLinkState's first,
second, seventh and eighth fields) and resetBasePositionAndOrientation are those of the *inertial* frame:
the centre of mass with the principal axes [checked: a base created at x = 1 with inertial frame
(0, 0, 0.5) reports z = 0.5; reset to (2, 0, 0) its box moves to z = -0.5]. The contract reports the body
frame, and the velocity of its origin: v_origin = v_com + omega x (origin - com).

getLinkState's link-frame fields (fifth and sixth, worldLinkFramePosition and -Orientation) are no way round
it: the C API computes them on the client (``b3GetLinkState``: com * inertial.inverse() in ``b3Transform``)
in Bullet3Common's ``b3Scalar``, which pybullet's build leaves single precision (only BT_USE_DOUBLE_PRECISION
is defined), and the quaternion comes back from a rotation matrix with its own sign [checked: every value
float32-representable; up to 1.5e-7 m and 2.2e-7 from this module's double-precision frames, and 8 of
pendulum5's 30 link quaternions of the opposite sign: tests/backends/test_pybullet_frames.py]. So links, like
bases, are converted here, in double precision: :class:`LinkFrames` on getLinkStates' tuples as they are read,
:class:`InertialFrames` for bases.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from typing import Any

import numpy as np

from ..geometry import IDENTITY, quat_conj, quat_mul, quat_rotate
from ..types import CompiledWorld, Quat, Vec3
from ._build import has_offset


def _cross(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _floats(*values: float) -> tuple[float, ...]:
    """As Python floats (a numpy scalar would make every operation on it several times slower)."""
    return tuple(float(v) for v in values)


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
    return _from_com(px, py, pz, bx, by, bz, bw, vx, vy, vz, ox, oy, oz, cx, cy, cz)


def _from_com(*row: Any) -> tuple[Any, ...]:
    """A row whose quaternion is already the body frame's (x y z w), with the COM (cx, cy, cz) in the body
    frame: its position and velocity moved from the COM to the frame's origin (``_inertial_to_body``'s end)."""
    px, py, pz, bx, by, bz, bw, vx, vy, vz, ox, oy, oz, cx, cy, cz = row
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
    """The bodies with an inertial offset, and the conversions of their states (``to_body``: of those not in
    ``links``, the bodies read as multibody links, which :class:`LinkFrames` converts)."""

    def __init__(self, world: CompiledWorld, links: Collection[int] = ()) -> None:
        self.offsets: dict[int, tuple[Vec3, Quat]] = {
            i: (b.com, b.inertia_quat) for i, b in enumerate(world.bodies) if has_offset(b)
        }
        converted = {i: frame for i, frame in self.offsets.items() if i not in set(links)}
        #: per converted body: its COM in the body frame and the conjugate of its principal axes' quaternion
        self._conj = [_floats(*com, *quat_conj(iq)) for com, iq in converted.values()]
        self._rows = np.array(list(converted), dtype=np.int64)
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


#: per link of a multibody: its COM in the body frame, the conjugate of its principal axes' quaternion (as floats)
#: and whether those axes are turned from the link's; None for a link without an inertial offset
LinkOffsets = list[tuple[float, float, float, float, float, float, float, bool] | None]


def _link_offset(com: Vec3, inertia_quat: Quat) -> tuple[float, float, float, float, float, float, float, bool]:
    (cx, cy, cz), (jw, jx, jy, jz) = com, quat_conj(inertia_quat)
    turned = tuple(inertia_quat) != IDENTITY
    return float(cx), float(cy), float(cz), float(jw), float(jx), float(jy), float(jz), turned


def _links_to_body(states: Sequence[Any], offsets: LinkOffsets) -> list[float]:
    """getLinkStates' tuples -> the links' rows (pos, quat x y z w, lin_vel, ang_vel) of their body frames, flat:
    :func:`_inertial_to_body`'s operations in its order (the same numbers, bit for bit), written out on the
    states' own floats with no intermediate array. Where the principal axes are the link's own (most URDFs'),
    the quaternion product with the identity's conjugate returns q, unless a component is an exact zero (whose
    sign the product may change): only then is it computed."""
    out: list[float] = []
    put = out.extend
    for ls, offset in zip(states, offsets, strict=True):
        if offset is None:
            put((*ls[0], *ls[1], *ls[6], *ls[7]))
            continue
        cx, cy, cz, jw, jx, jy, jz, turned = offset
        (px, py, pz), (x, y, z, w), (vx, vy, vz), (ox, oy, oz) = ls[0], ls[1], ls[6], ls[7]
        if turned or not (x and y and z and w):
            x, y, z, w = (w * jx + x * jw + y * jz - z * jy, w * jy - x * jz + y * jw + z * jx,
                          w * jz + x * jy - y * jx + z * jw, w * jw - x * jx - y * jy - z * jz)  # fmt: skip
        put(_from_com(px, py, pz, x, y, z, w, vx, vy, vz, ox, oy, oz, cx, cy, cz))
    return out


class LinkFrames:
    """One multibody's links, read as their body frames: ``rows(getLinkStates(...))``.

    The states' inertial frames are converted on the tuples getLinkStates returns, link by link on plain
    floats, straight into the flat list one ``fromiter`` makes the rows of: about 1 us per link beyond the
    engine call, where streaming the fields into an array and converting the rows after cost 2 to 3 [measured
    in-process, KUKA arm (7 offset links) and the bench's quadruped (12, turned principal axes): 12.3 and 22.9
    us with getLinkStates, against 23 and 45]. A whole-array conversion (tried: ten numpy calls on the read's
    array, 10-15 us for 7-12 links, and different rounding) would pay off only beyond about 40 links."""

    def __init__(self, world: CompiledWorld, bodies: Sequence[int]) -> None:
        specs = [world.bodies[i] for i in bodies]
        self.offsets: LinkOffsets = [_link_offset(b.com, b.inertia_quat) if has_offset(b) else None for b in specs]

    def rows(self, states: Sequence[Any]) -> np.ndarray:
        """(len(states), 13) rows of these links' body frames from getLinkStates' tuples (with velocities)."""
        values = _links_to_body(states, self.offsets)
        return np.fromiter(values, np.float64, len(values)).reshape(-1, 13)

    @classmethod
    def of(cls, world: CompiledWorld, bodies: Sequence[int]) -> LinkFrames | None:
        """The conversion for these links (one multibody's, in the order read); None if none is offset."""
        return cls(world, bodies) if any(has_offset(world.bodies[i]) for i in bodies) else None
