"""Panda3D's heading/pitch/roll convention (degrees, Z up, right-handed).

Column form T * Rh * Rp * Rr * S (panda3d-semantics notes §6): heading about +Z, pitch about +X,
roll about +Y, applied roll first. So q = q_h * q_p * q_r.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from backends.geometry import quat_from_axis_angle, quat_mul, quat_normalize


def hpr_to_quat(hpr: Sequence[float]) -> tuple[float, float, float, float]:
    h, p, r = (math.radians(a) for a in hpr)
    q = quat_mul(quat_from_axis_angle((0.0, 0.0, 1.0), h), quat_from_axis_angle((1.0, 0.0, 0.0), p))
    return quat_normalize(quat_mul(q, quat_from_axis_angle((0.0, 1.0, 0.0), r)))


def quat_to_hpr(q: Sequence[float]) -> tuple[float, float, float]:
    """Inverse of :func:`hpr_to_quat` (pitch in [-90, 90]); Panda3D's decomposition."""
    w, x, y, z = q
    # rotation matrix columns (R = Rz(h) Rx(p) Ry(r))
    r10 = 2 * (x * y + w * z)
    r11 = 1 - 2 * (x * x + z * z)
    r12 = 2 * (y * z - w * x)
    r21 = 2 * (y * z + w * x)
    r00 = 1 - 2 * (y * y + z * z)
    r20 = 2 * (x * z - w * y)
    r22 = 1 - 2 * (x * x + y * y)
    r01 = 2 * (x * y - w * z)
    pitch = math.asin(max(-1.0, min(1.0, r21)))
    if abs(r21) < 0.999999:
        heading = math.atan2(-r01, r11)
        roll = math.atan2(-r20, r22)
    else:  # gimbal lock: put everything into heading
        heading = math.atan2(r10, r00)
        roll = 0.0
    del r12
    return (math.degrees(heading), math.degrees(pitch), math.degrees(roll))
