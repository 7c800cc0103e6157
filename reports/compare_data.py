"""The comparison document: everything a report shows, as plain JSON data, from the runs alone.

``build_document(runs, reference=..., max_divergence=...)`` is a pure function of the files the runs
were read from (:mod:`reports.runs`): no clock, no absolute paths, stable ordering, floats rounded to the
traces' resolution. ``report.json`` is this document; the HTML and markdown pages are drawn from it
(plus the traces' poses, shapes and sounds for pictures and audio). The layout is documented in
docs/report-schema.md and checked by docs/report.schema.json; :mod:`reports.build` writes it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from importlib.metadata import PackageNotFoundError, version
from typing import Any

import numpy as np
import yaml

from backends.registry import REFERENCE_BACKEND
from reports import divergence as dv
from reports import trace_format as tf
from reports.events_data import compare_events, key_moments
from reports.runs import ReportError, Run
from reports.trace_reader import Trace

__all__ = ["REPORT_FORMAT", "build_document", "default_reference", "round9"]

REPORT_FORMAT = 1
REFERENCE_PREFERENCE = REFERENCE_BACKEND


def round9(x: float) -> float | None:
    """A float at the traces' resolution (1e-9), or None for NaN and infinities."""
    x = float(x)
    return round(x, 9) if np.isfinite(x) else None


def _series(values: np.ndarray) -> list[float | None]:
    return [round9(v) for v in values.tolist()]


def default_reference(backends: Sequence[str]) -> str:
    """``ode`` when it is among ``backends``, else the first in name order."""
    if not backends:
        raise ReportError("no backends to compare")
    return REFERENCE_PREFERENCE if REFERENCE_PREFERENCE in backends else sorted(backends)[0]


def _generator() -> str:
    try:
        return f"physics-scenarios {version('physics-scenarios')}"
    except PackageNotFoundError:  # pragma: no cover - a source tree without install
        return "physics-scenarios"


def _variant_order(runs: Sequence[Run]) -> dict[str, int]:
    """Variants in the order the scenario file declares them (from the YAML attached to a trace)."""
    for run in runs:
        if run.trace is None:
            continue
        name = run.trace.scenario.get(tf.KEY_SCENARIO_PATH, "")
        try:
            data = yaml.safe_load(run.trace.attachment(name))
        except (KeyError, yaml.YAMLError):
            continue
        variants = data.get("variants") if isinstance(data, dict) else None
        if isinstance(variants, dict):
            return {str(v): i for i, v in enumerate(variants)}
    return {}


def _cost(run: Run) -> dict[str, float | None]:
    steps = int(run.trace.times.size - 1) if run.has_steps and run.trace is not None else 0
    sim = float(run.trace.times[-1]) if run.has_steps and run.trace is not None else 0.0
    wall = run.wall_seconds
    return {
        "wall_seconds": wall,
        "steps": steps,
        "simulated_seconds": round9(sim),
        "steps_per_second": round(steps / wall, 3) if wall else None,
        "real_time_factor": round(sim / wall, 4) if wall else None,
    }


def _verdicts(run: Run) -> list[dict[str, Any]]:
    if run.trace is None:
        return []
    keep = ("passed", "measured", "expected", "time", "message", "kind")
    return [{"name": v.name, **{k: v.data.get(k) for k in keep}} for v in run.trace.verdicts]


def _verdict_matrix(runs: Sequence[Run]) -> dict[str, Any]:
    names: list[str] = []
    cells: dict[str, dict[str, Any]] = {}
    for run in runs:
        for v in _verdicts(run):
            if v["name"] not in cells:
                names.append(v["name"])
                cells[v["name"]] = {r.backend: None for r in runs}
            cells[v["name"]][run.backend] = {k: v[k] for k in ("passed", "measured", "expected", "time", "message")}
    return {"assertions": names, "cells": cells}


def _moving_bodies(trace: Trace) -> list[str]:
    specs = json.loads(trace.scenario.get(tf.KEY_BODY_SPECS, "[]"))
    static = {s["name"] for s in specs if s.get("motion") == "static"}
    return [b for b in trace.bodies if b not in static]


def _trajectory(run: Run) -> dict[str, Any] | None:
    if not run.has_steps or run.trace is None:
        return None
    t = run.trace
    bodies = {
        b: {axis: _series(t.bodies[b].pos[:, k]) for k, axis in enumerate(tf.VEC_KEYS)} for b in _moving_bodies(t)
    }
    joints = {j: _series(s.position) for j, s in t.joints.items() if np.isfinite(s.position).any()}
    return {"t": _series(t.times), "bodies": bodies, "joints": joints}


def _divergence(run: Run, ref: Run | None, thresholds: dict[str, float]) -> dict[str, Any]:
    if ref is None or not ref.has_steps or ref.trace is None:
        return {"available": False, "reason": "the reference has no recorded steps"}
    if not run.has_steps or run.trace is None:
        return {"available": False, "reason": "this run has no recorded steps"}
    where = dv.align(run.trace.times, ref.trace.times)
    if not where.times.size:
        return {"available": False, "reason": "no simulated time in common with the reference"}
    bodies: dict[str, Any] = {}
    series: dict[str, Any] = {"t": _series(where.times), "bodies": {}, "joints": {}}
    for body in _moving_bodies(ref.trace):
        if body not in run.trace.bodies:
            continue
        pos_err, ang_err = dv.body_errors(run.trace, ref.trace, body, where)
        bodies[body] = {
            "position": dv.stats(where.times, pos_err, thresholds["position"]),
            "angle": dv.stats(where.times, ang_err, thresholds["angle"]),
        }
        series["bodies"][body] = {"position": _series(pos_err), "angle": _series(ang_err)}
    joints: dict[str, Any] = {}
    for joint in ref.trace.joints:
        if joint not in run.trace.joints:
            continue
        jt, err = dv.joint_errors(run.trace, ref.trace, joint)
        if not np.isfinite(err).any():
            continue
        joints[joint] = dv.stats(jt, err, thresholds["joint"])
        series["joints"][joint] = {"t": _series(jt), "error": _series(err)}

    def worst(items: list[float | None]) -> float | None:
        vals = [x for x in items if x is not None]
        return max(vals) if vals else None

    return {
        "available": True,
        "compared_from": round9(where.times[0]),
        "compared_until": round9(where.times[-1]),
        "samples": int(where.times.size),
        "bodies": {b: {k: _rounded(s) for k, s in v.items()} for b, v in bodies.items()},
        "joints": {j: _rounded(s) for j, s in joints.items()},
        "max": {
            "position": round9(worst([v["position"]["max"] for v in bodies.values()]) or 0.0),
            "angle": round9(worst([v["angle"]["max"] for v in bodies.values()]) or 0.0),
            "joint": round9(worst([v["max"] for v in joints.values()]) or 0.0),
        },
        "series": series,
    }


def _rounded(s: dict[str, Any]) -> dict[str, Any]:
    return {k: round9(v) if isinstance(v, float) else v for k, v in s.items()}


def _run_entry(run: Run, div: dict[str, Any] | None, max_divergence: float | None) -> dict[str, Any]:
    verdicts = _verdicts(run)
    failed = sum(v["passed"] is not True for v in verdicts)
    within: bool | None = None
    if max_divergence is not None and div is not None and div.get("available"):
        within = max(div["max"]["position"] or 0.0, div["max"]["joint"] or 0.0) <= max_divergence
    return {
        "backend": run.backend,
        "engine_version": run.backend_version,
        "engine_settings": run.engine_settings,
        "trace": run.trace_name,
        "status": run.status,
        "label": run.label,
        "detail": run.detail,
        "passed": run.passed,
        "assertions": {"total": len(verdicts), "passed": len(verdicts) - failed, "failed": failed},
        "end_time": round9(run.trace.times[-1]) if run.has_steps and run.trace is not None else None,
        "outcome": run.outcome.to_json() if run.outcome is not None else None,
        "cost": _cost(run),
        "within_max_divergence": within,
        "ok": run.passed and within is not False,
    }


def _case(runs: list[Run], reference: str, thresholds: dict[str, float], max_div: float | None) -> dict[str, Any]:
    ref = next((r for r in runs if r.backend == reference), None)
    first = next((r for r in runs if r.trace is not None), None)
    meta = first.trace.scenario if first is not None and first.trace is not None else {}
    divergence = {r.backend: _divergence(r, ref, thresholds) for r in runs if r.backend != reference}
    return {
        "scenario": runs[0].scenario,
        "variant": runs[0].variant,
        "scenario_file": meta.get(tf.KEY_SCENARIO_PATH),
        "scenario_sha256": meta.get(tf.KEY_SCENARIO_SHA256),
        "dt": float(meta[tf.KEY_DT]) if tf.KEY_DT in meta else None,
        "duration": float(meta[tf.KEY_DURATION]) if tf.KEY_DURATION in meta else None,
        "reference": reference if ref is not None else None,
        "runs": [_run_entry(r, divergence.get(r.backend), max_div) for r in runs],
        "verdicts": _verdict_matrix(runs),
        "trajectories": {r.backend: _trajectory(r) for r in runs},
        "divergence": divergence,
        "events": compare_events(runs, reference),
        "sounds": {
            r.backend: [
                {"t": round9(s.t), "name": s.name, "action": s.action, "offset": s.offset, "volume": s.volume}
                for s in r.trace.sounds
            ]
            if r.trace is not None
            else []
            for r in runs
        },
        "key_moments": {r.backend: key_moments(r) for r in runs},
    }


def build_document(
    runs: Sequence[Run],
    *,
    reference: str | None = None,
    max_divergence: float | None = None,
    thresholds: dict[str, float] | None = None,
) -> dict[str, Any]:
    """The report as JSON data. ``reference`` defaults to :func:`default_reference` of the runs' backends;
    ``max_divergence`` (metres for bodies, joint units for joints) makes a larger error a failure and is
    also the threshold for "first time over" of positions and joints."""
    if not runs:
        raise ReportError("no runs to report on")
    names = sorted({r.backend for r in runs})
    reference = reference or default_reference(names)
    if reference not in names:
        raise ReportError(f"the reference `{reference}` is not among the runs' backends ({', '.join(names)})")
    limits = dict(dv.DEFAULT_THRESHOLDS, **(thresholds or {}))
    if max_divergence is not None:
        limits["position"] = limits["joint"] = float(max_divergence)
    backends = [reference, *[n for n in names if n != reference]]
    rank = {b: i for i, b in enumerate(backends)}
    groups: dict[tuple[str, str], list[Run]] = {}
    for run in runs:
        groups.setdefault((run.scenario, run.variant), []).append(run)
    orders = {s: _variant_order([r for r in runs if r.scenario == s]) for s, _ in groups}
    keys = sorted(groups, key=lambda k: (k[0], orders[k[0]].get(k[1], len(orders[k[0]])), k[1]))
    cases = [_case(sorted(groups[k], key=lambda r: rank[r.backend]), reference, limits, max_divergence) for k in keys]
    all_runs = [r for c in cases for r in c["runs"]]
    return {
        "report_format": REPORT_FORMAT,
        "generator": _generator(),
        "reference": reference,
        "backends": backends,
        "thresholds": {k: round9(v) for k, v in limits.items()},
        "max_divergence": max_divergence,
        "passed": all(r["ok"] for r in all_runs),
        "summary": {
            "cases": len(cases),
            "runs": len(all_runs),
            "ok": sum(r["ok"] for r in all_runs),
            "not_ok": sum(not r["ok"] for r in all_runs),
        },
        "cases": cases,
    }
