"""How far a run drifts from the reference: aligned series, position and orientation errors, statistics.

Runs of one case share ``dt``, so their samples fall on the same simulated times (integer nanoseconds in
the trace) and are compared sample by sample over the times both have (a crashed or failed run stops
early). If the times differ (another ``dt``), the reference is interpolated linearly onto the run's
times inside the common span (quaternions component-wise, then normalised).

* position error: |p - p_ref| (metres);
* orientation error: the angle of the rotation between the two orientations,
  2 atan2(|v|, |w|) of q_ref^-1 q (radians, in [0, pi]), insensitive to the quaternion's sign;
* joint error: |position - position_ref| (metres for sliders, radians for hinges).

For each: the largest value and when, the RMS over the compared samples, and the first time it exceeds
a threshold (None if never).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from reports.trace_reader import Trace

__all__ = ["Aligned", "DEFAULT_THRESHOLDS", "align", "body_errors", "joint_errors", "quat_angle", "stats"]

#: thresholds for "first time over" when the caller gives none, one per physical kind: positions 1 cm (about
#: the contact slop engines allow: ODE's resting depth, DART's 6.7 mm after a landing, docs/semantics.md),
#: angles 5 degrees (a turn a reader sees in a picture)
DEFAULT_THRESHOLDS: dict[str, float] = {"position": 0.01, "angle": math.radians(5.0)}


@dataclass
class Aligned:
    """Sample indices (or interpolation) that put a run beside the reference."""

    times: np.ndarray
    run_index: np.ndarray  # indices into the run's samples
    ref_index: np.ndarray | None  # indices into the reference's samples, or None: interpolate
    ref_times: np.ndarray

    def ref_values(self, values: np.ndarray) -> np.ndarray:
        if self.ref_index is not None:
            return values[self.ref_index]
        cols = values.reshape(len(self.ref_times), -1)
        out = np.column_stack([np.interp(self.times, self.ref_times, cols[:, k]) for k in range(cols.shape[1])])
        return out.reshape((len(self.times), *values.shape[1:]))


def align(run_times: np.ndarray, ref_times: np.ndarray) -> Aligned:
    """Put the run's samples beside the reference's over the span both cover."""
    run_ns = np.rint(np.asarray(run_times, float) * 1e9).astype(np.int64)
    ref_ns = np.rint(np.asarray(ref_times, float) * 1e9).astype(np.int64)
    if run_ns.size == 0 or ref_ns.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return Aligned(np.zeros(0), empty, empty, np.asarray(ref_times, float))
    common, run_idx, ref_idx = np.intersect1d(run_ns, ref_ns, assume_unique=True, return_indices=True)
    n = min(run_ns.size, ref_ns.size)
    if common.size == n and np.array_equal(run_ns[:n], ref_ns[:n]):
        return Aligned(run_times[:n].astype(float), np.arange(n), np.arange(n), np.asarray(ref_times, float))
    lo, hi = max(run_ns[0], ref_ns[0]), min(run_ns[-1], ref_ns[-1])
    inside = np.flatnonzero((run_ns >= lo) & (run_ns <= hi))
    return Aligned(np.asarray(run_times, float)[inside], inside, None, np.asarray(ref_times, float))


def quat_angle(q_ref: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Angles (rad) of the rotations taking each ``q_ref`` to ``q``; rows (w, x, y, z), any norm."""
    a = q_ref / np.linalg.norm(q_ref, axis=1, keepdims=True)
    b = q / np.linalg.norm(q, axis=1, keepdims=True)
    # r = conj(a) * b
    w = np.sum(a * b, axis=1)
    v = a[:, :1] * b[:, 1:] - b[:, :1] * a[:, 1:] - np.cross(a[:, 1:], b[:, 1:])
    return 2.0 * np.arctan2(np.linalg.norm(v, axis=1), np.abs(w))


def stats(times: np.ndarray, errors: np.ndarray, threshold: float) -> dict[str, Any]:
    """max (and when), RMS, and the first time over ``threshold``, of the finite ``errors``."""
    ok = np.isfinite(errors)
    if not ok.any():
        return {"max": None, "max_time": None, "rms": None, "threshold": threshold, "first_over": None}
    t, e = times[ok], errors[ok]
    k = int(np.argmax(e))
    over = np.flatnonzero(e > threshold)
    return {
        "max": float(e[k]),
        "max_time": float(t[k]),
        "rms": float(np.sqrt(np.mean(e * e))),
        "threshold": threshold,
        "first_over": float(t[over[0]]) if over.size else None,
    }


def body_errors(run: Trace, ref: Trace, body: str, where: Aligned) -> tuple[np.ndarray, np.ndarray]:
    """(position error, orientation angle) of ``body`` at ``where.times``."""
    mine, theirs = run.bodies[body], ref.bodies[body]
    pos = mine.pos[where.run_index]
    quat = mine.quat[where.run_index]
    ref_pos = where.ref_values(theirs.pos)
    ref_quat = where.ref_values(theirs.quat)
    if where.ref_index is None and len(ref_quat):
        ref_quat = ref_quat / np.linalg.norm(ref_quat, axis=1, keepdims=True)
    return np.linalg.norm(pos - ref_pos, axis=1), quat_angle(ref_quat, quat) if len(quat) else np.zeros(0)


def joint_errors(run: Trace, ref: Trace, joint: str) -> tuple[np.ndarray, np.ndarray]:
    """(times, |position - reference position|) of ``joint`` (NaN where a joint has no position)."""
    where = align(run.joint_times, ref.joint_times)
    if not where.times.size:
        return np.zeros(0), np.zeros(0)
    mine = run.joints[joint].position[where.run_index]
    theirs = where.ref_values(ref.joints[joint].position)
    return where.times, np.abs(mine - theirs)
