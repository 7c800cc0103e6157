"""Small quaternion helpers in (w, x, y, z) order, shared by the runner and the backends."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

#: A 3- or 4-vector: a tuple, a list or a numpy row.
Vector = Sequence[float] | np.ndarray

IDENTITY: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


def quat_mul(a: Vector, b: Vector) -> tuple[float, float, float, float]:
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def quat_conj(q: Vector) -> tuple[float, float, float, float]:
    return (q[0], -q[1], -q[2], -q[3])


def quat_normalize(q: Vector) -> tuple[float, float, float, float]:
    n = math.sqrt(sum(c * c for c in q))
    if n == 0.0 or not math.isfinite(n):
        raise ValueError(f"cannot normalise quaternion {tuple(q)}")
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def quat_from_axis_angle(axis: Vector, angle: float) -> tuple[float, float, float, float]:
    n = math.sqrt(sum(c * c for c in axis))
    if n == 0.0:
        return IDENTITY
    s = math.sin(angle / 2.0) / n
    return (math.cos(angle / 2.0), axis[0] * s, axis[1] * s, axis[2] * s)


def quat_rotate(q: Vector, v: Vector) -> tuple[float, float, float]:
    w, x, y, z = q
    # v' = v + 2w (u x v) + 2 u x (u x v), u = (x, y, z)
    cx = y * v[2] - z * v[1]
    cy = z * v[0] - x * v[2]
    cz = x * v[1] - y * v[0]
    return (
        v[0] + 2.0 * (w * cx + y * cz - z * cy),
        v[1] + 2.0 * (w * cy + z * cx - x * cz),
        v[2] + 2.0 * (w * cz + x * cy - y * cx),
    )


def rotation_vector(q_from: Vector, q_to: Vector) -> tuple[float, float, float]:
    """The world-frame rotation vector (axis * angle) that turns ``q_from`` into ``q_to`` (shortest)."""
    d = quat_mul(q_to, quat_conj(q_from))
    if d[0] < 0.0:
        d = (-d[0], -d[1], -d[2], -d[3])
    s = math.sqrt(d[1] * d[1] + d[2] * d[2] + d[3] * d[3])
    if s < 1e-15:
        return (0.0, 0.0, 0.0)
    angle = 2.0 * math.atan2(s, d[0])
    return (d[1] / s * angle, d[2] / s * angle, d[3] / s * angle)


def integrate_quat(q: Vector, ang_vel: Vector, dt: float) -> tuple[float, float, float, float]:
    """Rotate ``q`` by the world-frame angular velocity over ``dt`` (exact for constant velocity)."""
    w = math.sqrt(sum(c * c for c in ang_vel))
    if w == 0.0:
        return (q[0], q[1], q[2], q[3])
    return quat_normalize(quat_mul(quat_from_axis_angle(ang_vel, w * dt), q))


def quat_matrices(q: Vector | np.ndarray) -> np.ndarray:
    """Rotation matrices of (w, x, y, z) quaternions, normalised first (a zero one is the identity): one
    (3, 3) matrix for a 4-vector, (N, 3, 3) for an (N, 4) array."""
    a = np.asarray(q, dtype=np.float64)
    n = np.linalg.norm(a, axis=-1, keepdims=True)
    a = a / np.where(n > 0.0, n, 1.0) + np.where(n > 0.0, 0.0, np.array([1.0, 0.0, 0.0, 0.0]))
    w, x, y, z = np.moveaxis(a, -1, 0)
    rows = (
        (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def quats_xyzw_to_wxyz(q: np.ndarray) -> np.ndarray:
    return q[..., [3, 0, 1, 2]]


def quats_wxyz_to_xyzw(q: np.ndarray) -> np.ndarray:
    return q[..., [1, 2, 3, 0]]
