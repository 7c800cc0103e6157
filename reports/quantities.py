"""The quantities a report compares, each against its truth (reports.truth), with one threshold per
physical kind: metres for positions (bodies, sliders, how far a body strays from its joint), radians
for angles (orientations, hinges, tilts), whichever view shows them.

For every case:

* analytic references given by the caller (:class:`reports.truth.Reference`), one quantity each;
* for a body held by a joint to the environment, what the joint forbids, against 0: off its line
  (slider), away from its anchor (hinge, ball, universal), away from its place (fixed), and its tilt or
  axis drift (rad). Its free motion is the joint's own coordinate, where no truth is known;
* where no truth is known: every other moving body's position (m) and orientation (rad), and every
  joint's position (m for a slider, rad for a hinge). The engines are compared with each other
  (reports.consensus: pairwise deviations, groups, the engines that depart from a majority), or, when
  the caller names a reference engine (``--reference``), each against that engine's run.

A quantity's deviation per run: the largest value and when, the RMS, the first time over the threshold,
and the series (for the charts). Against a truth every run is measured; among the engines, each run's
deviation from those it is judged with; against a named reference engine, the others only.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from reports import divergence as dv
from reports import trace_format as tf
from reports.consensus import Pair, judge
from reports.runs import Run
from reports.trace_reader import Trace
from reports.truth import Reference

__all__ = ["KINDS", "UNITS", "Quantity", "measure", "quantities", "specs", "truth_wins"]

KINDS = ("position", "angle")
UNITS = {"position": "m", "angle": "rad"}
_STEADY = ("slider", "hinge", "ball", "universal", "fixed")


@dataclass
class Quantity:
    """One quantity before it is measured: against a truth (``errors`` per backend) or among the engines
    (``pairs``: each pair's deviation from each other)."""

    id: str
    label: str
    kind: str
    truth: dict[str, Any]
    errors: dict[str, tuple[np.ndarray, np.ndarray]]  # backend -> (times, deviation)
    pairs: dict[tuple[str, str], Pair] | None = None  # among the engines: (a, b) -> (times, deviation)


def _r(x: float) -> float | None:
    x = float(x)
    return round(x, 9) if math.isfinite(x) else None


def specs(trace: Trace, key: str) -> list[dict[str, Any]]:
    """The scenario's JSON list under ``key`` in the trace (body or joint specs); [] when unreadable."""
    try:
        found = json.loads(trace.scenario.get(key, "[]"))
    except (json.JSONDecodeError, RecursionError):
        return []
    return [s for s in found if isinstance(s, dict)] if isinstance(found, list) else []


def _rot(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) of quaternions (n, 4) w x y z."""
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1),
    ], axis=1)  # fmt: skip


def _constraint_errors(trace: Trace, joint: dict[str, Any], body: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(distance error in m, angle error in rad) of ``body`` from what ``joint`` to the environment allows."""
    series = trace.bodies[body["name"]]
    p, q = series.pos, series.quat
    p0, q0 = np.asarray(body["pos"], float), np.asarray(body["quat"], float)
    axis = np.asarray(joint.get("axis") or (1.0, 0.0, 0.0), float)
    axis = axis / (np.linalg.norm(axis) or 1.0)
    kind = joint["kind"]
    tilt = dv.quat_angle(np.tile(q0, (len(q), 1)), q) if len(q) else np.zeros(0)
    if kind == "slider":
        d = p - p0
        return np.linalg.norm(d - np.outer(d @ axis, axis), axis=1), tilt
    if kind == "fixed":
        return np.linalg.norm(p - p0, axis=1), tilt
    anchor = np.asarray(joint.get("anchor") or p0, float)
    r0 = _rot(q0[None, :])[0]
    local = r0.T @ (anchor - p0)  # the body's material point at the anchor
    rot = _rot(q) if len(q) else np.zeros((0, 3, 3))
    drift = np.linalg.norm(p + rot @ local - anchor, axis=1)
    if kind == "hinge":
        turned = rot @ (r0.T @ axis)
        return drift, np.arccos(np.clip(turned @ axis, -1.0, 1.0))
    return drift, np.full(len(p), np.nan)


def _joint_label(kind: str) -> tuple[str, str]:
    return {
        "slider": ("off the slider's line", "tilt"),
        "hinge": ("away from the hinge's anchor", "hinge axis drift"),
        "fixed": ("away from its fixed place", "tilt"),
    }.get(kind, (f"away from the {kind} joint's anchor", ""))


def _moving(trace: Trace) -> list[str]:
    static = {s["name"] for s in specs(trace, tf.KEY_BODY_SPECS) if s.get("motion") == "static"}
    return [b for b in trace.bodies if b not in static]


def _vs_reference(runs: Sequence[Run], ref: Run | None, get: Any) -> dict[str, tuple[np.ndarray, ...]]:
    out: dict[str, tuple[np.ndarray, ...]] = {}
    if ref is None or not ref.has_steps or ref.trace is None:
        return out
    for run in runs:
        if run is ref or not run.has_steps or run.trace is None:
            continue
        found = get(run.trace, ref.trace)
        if found is not None:
            out[run.backend] = found
    return out


def _pairwise(runs: Sequence[Run], get: Any) -> dict[tuple[str, str], tuple[np.ndarray, ...]]:
    """Every pair of runs with steps (in report order), measured against each other by ``get``."""
    ready = [r for r in runs if r.has_steps and r.trace is not None]
    out: dict[tuple[str, str], tuple[np.ndarray, ...]] = {}
    for i, a in enumerate(ready):
        for b in ready[i + 1 :]:
            found = get(b.trace, a.trace)
            if found is not None:
                out[(a.backend, b.backend)] = found
    return out


def _compared(runs: Sequence[Run], ref: Run | None, explicit: bool, get: Any,
              columns: Sequence[int]) -> list[tuple[dict[str, Any], dict[tuple[str, str], Pair] | None]]:  # fmt: skip
    """Per column of ``get``'s answer: (each run's errors against the named reference, None) or ({}, the
    pairs among the engines)."""
    if explicit:
        per = _vs_reference(runs, ref, get)
        return [({b: (e[0], e[c]) for b, e in per.items()}, None) for c in columns]
    pairs = _pairwise(runs, get)
    return [({}, {k: (e[0], e[c]) for k, e in pairs.items()}) for c in columns]


def _body_errors(body: str) -> Any:
    def get(run: Trace, ref: Trace) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        if body not in run.bodies or body not in ref.bodies:
            return None
        where = dv.align(run.times, ref.times)
        if not where.times.size:
            return None
        pos, ang = dv.body_errors(run, ref, body, where)
        return where.times, pos, ang

    return get


def _joint_errors(joint: str) -> Any:
    def get(run: Trace, ref: Trace) -> tuple[np.ndarray, np.ndarray] | None:
        if joint not in run.joints or joint not in ref.joints:
            return None
        t, err = dv.joint_errors(run, ref, joint)
        return (t, err) if np.isfinite(err).any() else None

    return get


def _analytic(runs: Sequence[Run], ref: Reference) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    out = {}
    truth_t = np.asarray(ref.times, float)
    truth_v = np.asarray(ref.values, float)
    for run in runs:
        if run.trace is None or not run.has_steps:
            continue
        try:
            t, v = run.trace.series(ref.signal)
        except KeyError:
            continue
        inside = (t >= truth_t[0] - 1e-9) & (t <= truth_t[-1] + 1e-9)
        t = np.asarray(t, float)[inside]
        out[run.backend] = (t, np.abs(np.asarray(v, float)[inside] - np.interp(t, truth_t, truth_v)))
    return out


def _collect(runs: Sequence[Run], ref: Run | None, references: Sequence[Reference],
             explicit: bool) -> list[Quantity]:  # fmt: skip
    found: list[Quantity] = []
    for r in references:
        kind = r.kind if r.kind in KINDS else "position"
        found.append(Quantity(f"analytic:{r.signal}", r.label or r.signal, kind,
                               {"kind": "analytic", "source": r.source}, _analytic(runs, r)))  # fmt: skip
    first = next((r.trace for r in ([ref] if ref else []) + list(runs) if r is not None and r.trace is not None), None)
    if first is None:
        return found
    bodies = {s["name"]: s for s in specs(first, tf.KEY_BODY_SPECS)}
    joints = specs(first, tf.KEY_JOINT_SPECS)
    held: set[str] = set()
    for j in joints:
        body = bodies.get(j.get("body", ""))
        if j.get("other") is not None or j.get("kind") not in _STEADY or body is None or "pos" not in body:
            continue
        held.add(body["name"])
        dist_label, angle_label = _joint_label(j["kind"])
        errors = {r.backend: (r.trace.times, *_constraint_errors(r.trace, j, body))
                  for r in runs if r.trace is not None and r.has_steps and body["name"] in r.trace.bodies}  # fmt: skip
        what = {"slider": f"moves only along {tuple(j['axis'])}", "fixed": "does not move"}.get(
            j["kind"], f"keeps its anchor at {tuple(j.get('anchor') or ())}")
        truth = {"kind": "constraint", "source": f"{j['kind']} `{j['name']}` to the environment: {body['name']} {what}"}
        found.append(Quantity(f"{body['name']}:joint-distance", f"{body['name']} {dist_label}", "position", truth,
                               {b: (e[0], e[1]) for b, e in errors.items()}))  # fmt: skip
        if angle_label and j["kind"] != "ball" and j["kind"] != "universal":
            found.append(Quantity(f"{body['name']}:joint-angle", f"{body['name']} {angle_label}", "angle", truth,
                                   {b: (e[0], e[2]) for b, e in errors.items()}))  # fmt: skip
    ref_truth: dict[str, Any] = {"kind": "reference", "backend": ref.backend if ref else None} if explicit \
        else {"kind": "engines"}  # fmt: skip
    for name in _moving(first):
        if name in held:
            continue
        (pos, pos_pairs), (ang, ang_pairs) = _compared(runs, ref, explicit, _body_errors(name), (1, 2))
        found.append(Quantity(f"{name}:position", f"{name} position", "position", ref_truth, pos, pos_pairs))
        found.append(Quantity(f"{name}:orientation", f"{name} orientation", "angle", ref_truth, ang, ang_pairs))
    for j in joints:
        if j.get("kind") not in ("slider", "hinge") or j["name"] not in first.joints:
            continue
        ((per, pairs),) = _compared(runs, ref, explicit, _joint_errors(j["name"]), (1,))
        kind = "position" if j["kind"] == "slider" else "angle"
        found.append(Quantity(f"{j['name']}:position", f"{j['name']} {'position' if kind == 'position' else 'angle'}",
                               kind, ref_truth, per, pairs))  # fmt: skip
    return found


def _series(values: np.ndarray) -> list[float | None]:
    return [_r(v) for v in np.asarray(values, float).tolist()]


def quantities(runs: Sequence[Run], ref: Run | None, thresholds: dict[str, float],
               references: Sequence[Reference] = (), explicit: bool = False) -> list[dict[str, Any]]:  # fmt: skip
    """Every quantity of one case (see the module docstring) with each run's deviation from its truth;
    ``explicit``: the caller named ``ref`` (--reference), so where no truth is known runs are measured
    against it rather than against each other."""
    backends = [r.backend for r in runs]
    ready = [r.backend for r in runs if r.has_steps and r.trace is not None]
    return [measure(q, backends, ready, thresholds[q.kind]) for q in _collect(runs, ref, references, explicit)]


def measure(q: Quantity, backends: Sequence[str], ready: Sequence[str], limit: float) -> dict[str, Any]:
    """A quantity as the comparison document holds it: each of ``backends``' deviation from its truth, or, for
    a quantity among the engines, the judgement of the engines in ``ready`` (runs with steps) by each other."""
    verdict = None
    errors = q.errors
    if q.pairs is not None:
        verdict = judge([b for b in ready if any(b in k for k in q.pairs)] or list(ready), q.pairs, limit)
        errors = verdict.series
    deviation: dict[str, Any] = {}
    series: dict[str, Any] = {}
    for backend in backends:
        if backend not in errors:
            continue
        t, err = errors[backend]
        s = dv.stats(np.asarray(t, float), np.asarray(err, float), limit)
        deviation[backend] = {k: _r(v) if isinstance(v, float) else v for k, v in s.items() if k != "threshold"}
        series[backend] = {"t": _series(t), "deviation": _series(err)}
    if verdict is None:
        diverging = [b for b, d in deviation.items() if d["first_over"] is not None]
        firsts = [deviation[b]["first_over"] for b in diverging]
    else:
        diverging = [d["backend"] for d in verdict.departures]
        firsts = [d["from"] for d in verdict.departures]
    entry = {
        "id": q.id, "label": q.label, "kind": q.kind, "unit": UNITS[q.kind], "threshold": _r(limit),
        "truth": q.truth, "deviation": deviation, "diverging": diverging,
        "first_over": min(firsts) if firsts else None, "series": series,
    }  # fmt: skip
    if verdict is not None:
        entry["agreement"] = verdict.to_json()
    return entry


def truth_wins(qs: Sequence[dict[str, Any]], stated: Sequence[dict[str, Any]] = ()) -> None:
    """Where the engines of a majority miss a known truth (a joint's constraint, an analytic reference, a value
    an assertion states) that an engine departing from them meets, that engine is not named: its departures
    are marked ``overruled`` and leave the quantity's ``diverging``."""
    missing = {b for q in qs if q["truth"]["kind"] in ("constraint", "analytic") for b in q["diverging"]}
    missing |= {b for row in stated for b, cell in row["cells"].items() if cell["passed"] is not True}
    for q in qs:
        verdict = q.get("agreement")
        if verdict is None:
            continue
        for d in verdict["departures"]:
            d["overruled"] = set(d["majority"]) <= missing and d["backend"] not in missing
        named = [d for d in verdict["departures"] if not d["overruled"]]
        q["diverging"] = [d["backend"] for d in named]
        q["first_over"] = min((d["from"] for d in named), default=None)
