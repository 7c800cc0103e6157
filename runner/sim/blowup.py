"""The runner's blow-up check, the one limit for every engine (docs/semantics.md, "Blow-ups")."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from backends.types import BodyStates

if TYPE_CHECKING:
    from runner.sim.resolver import Snapshot

#: The one blow-up limit, for every engine (docs/semantics.md, "Blow-ups"): a body whose state is not finite,
#: or whose linear (m/s) or angular (rad/s) speed exceeds this, has blown up. Adapters check nothing
#: themselves beyond what their engine calls fatal (backends/base.py).
MAX_SPEED = 1.0e4


_MAX_SPEED_SQUARED = MAX_SPEED * MAX_SPEED  # 1e8, exact: |v|^2 <= it  <=>  |v| <= MAX_SPEED (sqrt is monotone)
_FAST_LIMIT = _MAX_SPEED_SQUARED * (1.0 - 1e-9)  # the sums' fast test: far more than any rounding below the limit


def blown_up(states: BodyStates) -> tuple[int, bool] | None:
    """The first body whose state is not finite or too fast, and whether it is not finite; None if none.

    Every step checks every body, so the common case (all well) is four whole-array calls: the sums of the
    squared speeds over all bodies bound each body's (a sum of non-negative terms is at least each of them;
    a NaN or an inf makes the sum fail the comparison, and the positions' and quaternions' sums of squares
    are not finite when an element is not, or when one is beyond 1e154, which the exact test then clears),
    held a little below the limit so that no rounding of the sums can let a body through. Anything else
    takes the exact per-body test.
    """
    lin, ang = states.lin_vel, states.ang_vel
    if not len(lin) or (
        float(np.vdot(lin, lin)) <= _FAST_LIMIT
        and float(np.vdot(ang, ang)) <= _FAST_LIMIT
        and math.isfinite(float(np.vdot(states.pos, states.pos)) + float(np.vdot(states.quat, states.quat)))
    ):
        return None
    lin2, ang2 = np.add.reduce(lin * lin, axis=1), np.add.reduce(ang * ang, axis=1)
    if (
        np.isfinite(states.pos).all()
        and np.isfinite(states.quat).all()
        and float(lin2.max()) <= _MAX_SPEED_SQUARED
        and float(ang2.max()) <= _MAX_SPEED_SQUARED
    ):
        return None
    bad = ~(
        np.isfinite(states.pos).all(axis=1)
        & np.isfinite(states.quat).all(axis=1)
        & np.isfinite(lin).all(axis=1)
        & np.isfinite(ang).all(axis=1)
    )
    fast = (np.linalg.norm(np.nan_to_num(lin, nan=np.inf), axis=1) > MAX_SPEED) | (
        np.linalg.norm(np.nan_to_num(ang, nan=np.inf), axis=1) > MAX_SPEED
    )
    broken = np.flatnonzero(bad | fast)
    if not broken.size:
        return None
    i = int(broken[0])
    return i, bool(bad[i])


def last_good(snapshot: Snapshot, i: int) -> dict[str, Any] | None:
    """Body ``i``'s last state that passed the checks, as every engine failure reports it."""
    return last_good_state(snapshot.time, snapshot.bodies, i)


def last_good_state(time: float, last: BodyStates, i: int) -> dict[str, Any] | None:
    """Body ``i``'s state in ``last``, read at ``time``, as an engine failure reports its last good state."""
    if not len(last.pos):  # nothing read yet
        return None
    return {
        "time": time,
        "pos": last.pos[i].tolist(),
        "vel": last.lin_vel[i].tolist(),
        "angvel": last.ang_vel[i].tolist(),
    }
