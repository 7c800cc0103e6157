"""A named frame fixed on a body (an MJCF site, a merged URDF link: ``Program.frames``), as expressions read it.

With the body's state (``p``, ``R``, ``v`` the velocity of its origin, ``w``) and the frame's place in the body
frame (``r``, ``q``): ``pos = p + R r``, ``quat = q_body q``, ``vel = v + w x (R r)`` (the velocity of the frame's
origin) and ``angvel = w``, all in the world frame, as a body's own fields are.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from backends.geometry import quat_matrices, quat_mul
from backends.types import BodyStates, Quat, Vec3

__all__ = ["frame_getter"]

_AXES = {"x": 0, "y": 1, "z": 2}
_QUAT = {"w": 0, "x": 1, "y": 2, "z": 3}


def frame_getter(row: int, pos: Vec3, quat: Quat, field: str, component: str,
                 states: Callable[[], BodyStates]) -> Callable[[], float]:  # fmt: skip
    """A getter of ``<frame>.<field>.<component>`` for a frame at ``pos``/``quat`` on the body at ``row``."""
    local = np.asarray(pos, float)
    if field == "quat":
        col = _QUAT[component]
        return lambda: float(quat_mul(states().quat[row], quat)[col])
    col = _AXES[component]
    if field == "angvel":
        return lambda: float(states().ang_vel[row, col])

    def value() -> float:
        s = states()
        arm = quat_matrices(s.quat[row]) @ local
        if field == "pos":
            return float(s.pos[row, col] + arm[col])
        return float(s.lin_vel[row, col] + np.cross(s.ang_vel[row], arm)[col])

    return value
