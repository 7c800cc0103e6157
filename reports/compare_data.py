"""The comparison document: everything a report shows, as plain JSON data, from the runs alone.

``build_document(runs, reference=..., max_divergence=...)`` is a pure function of the files the runs
were read from (:mod:`reports.runs`): no clock, no absolute paths, stable ordering, floats rounded to the
traces' resolution. ``report.json`` is this document; the HTML and markdown pages are drawn from it
(plus the traces' poses, shapes and sounds for pictures and audio). The layout is documented in
docs/report-schema.md and checked by docs/report.schema.json; :mod:`reports.build` writes it.

Each case says first how every engine compares with the truth where one is known (values the
assertions state, analytic references, what joints allow: reports.truth), then how the engines compare
with each other where none is (reports.quantities, reports.consensus; with an explicit ``reference``,
how each compares with that engine's run), why an engine departs where the data show it
(reports.causes), and a headline that keeps assertions and agreement apart (reports.headline).
"""

from __future__ import annotations

from collections.abc import Sequence
from importlib.metadata import PackageNotFoundError, version
from typing import Any

import numpy as np
import yaml

from backends.registry import REFERENCE_BACKEND
from reports import divergence as dv
from reports import trace_format as tf
from reports.causes import joint_sag
from reports.events_data import compare_events
from reports.headline import headline, merge
from reports.moments import key_moments
from reports.quantities import KINDS, UNITS, quantities, truth_wins
from reports.quantities import specs as body_joint_specs
from reports.runs import ReportError, Run
from reports.trace_reader import Trace
from reports.truth import Reference, stated_values

__all__ = ["REPORT_FORMAT", "build_document", "default_reference", "round9"]

REPORT_FORMAT = 3
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
    keep = ("passed", "measured", "expected", "time", "message", "kind", "known_limit")
    return [{"name": v.name, "status": v.status, **{k: v.data.get(k) for k in keep}} for v in run.trace.verdicts]


def _verdict_matrix(runs: Sequence[Run]) -> dict[str, Any]:
    names: list[str] = []
    cells: dict[str, dict[str, Any]] = {}
    for run in runs:
        for v in _verdicts(run):
            if v["name"] not in cells:
                names.append(v["name"])
                cells[v["name"]] = {r.backend: None for r in runs}
            keys = ("passed", "status", "measured", "expected", "time", "message", "known_limit")
            cells[v["name"]][run.backend] = {k: v[k] for k in keys}
    return {"assertions": names, "cells": cells}


def _moving_bodies(trace: Trace) -> list[str]:
    specs = body_joint_specs(trace, tf.KEY_BODY_SPECS)
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


def _within(backend: str, qs: list[dict[str, Any]], max_divergence: float | None) -> bool | None:
    """Whether every position quantity of ``backend`` stays within ``max_divergence`` metres (None without it)."""
    if max_divergence is None:
        return None
    worst = [q["deviation"][backend]["max"] for q in qs if q["kind"] == "position" and backend in q["deviation"]]
    return all(w is None or w <= max_divergence for w in worst)


def _run_entry(run: Run, qs: list[dict[str, Any]], max_divergence: float | None) -> dict[str, Any]:
    verdicts = _verdicts(run)
    failed = sum(v["passed"] is not True for v in verdicts)
    limits = sum(v["status"] == "known limit" for v in verdicts)  # expected failures: not passes, not failures
    within = _within(run.backend, qs, max_divergence)
    diverging = [q["id"] for q in qs if run.backend in q["diverging"]]
    firsts = [q["deviation"][run.backend]["first_over"] for q in qs if run.backend in q["diverging"]]
    return {
        "backend": run.backend,
        "engine_version": run.backend_version,
        "engine_settings": run.engine_settings,
        "trace": run.trace_name,
        "status": run.status,
        "label": run.label,
        "detail": run.detail,
        "passed": run.passed,
        "assertions": {
            "total": len(verdicts),
            "passed": len(verdicts) - failed - limits,
            "failed": failed,
            "known_limits": limits,
        },
        "agreement": {"diverging": diverging, "first_over": min(firsts) if firsts else None},
        "end_time": round9(run.trace.times[-1]) if run.has_steps and run.trace is not None else None,
        "outcome": run.outcome.to_json() if run.outcome is not None else None,
        "cost": _cost(run),
        "within_max_divergence": within,
        "ok": run.passed and within is not False,
    }


def _case(runs: list[Run], reference: str, thresholds: dict[str, float], max_div: float | None,
          references: list[Reference], explicit: bool, required: bool) -> dict[str, Any]:  # fmt: skip
    ref = next((r for r in runs if r.backend == reference), None)
    first = next((r for r in runs if r.trace is not None), None)
    meta = first.trace.scenario if first is not None and first.trace is not None else {}
    qs = quantities(runs, ref, thresholds, references, explicit)
    stated = stated_values(runs)
    truth_wins(qs, stated)
    entries = [_run_entry(r, qs, max_div) for r in runs]
    departing = [d["backend"] for q in qs for d in q.get("agreement", {}).get("departures", [])]
    causes = joint_sag(runs, qs, departing)
    dt = float(meta[tf.KEY_DT]) if tf.KEY_DT in meta else None
    duration = float(meta[tf.KEY_DURATION]) if tf.KEY_DURATION in meta else None
    case: dict[str, Any] = {
        "scenario": runs[0].scenario,
        "variant": runs[0].variant,
        "scenario_file": meta.get(tf.KEY_SCENARIO_PATH),
        "scenario_sha256": meta.get(tf.KEY_SCENARIO_SHA256),
        "dt": dt,
        "duration": duration,
        "reference": reference if ref is not None else None,
        "headline": headline(entries, qs, causes, required),
        "runs": entries,
        "verdicts": _verdict_matrix(runs),
        "stated": stated,
        "quantities": qs,
        "trajectories": {r.backend: _trajectory(r) for r in runs},
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
    }
    ends = [e["end_time"] for e in entries if e["end_time"] is not None]
    case["key_moments"] = key_moments(case, max(ends + [0.0]), dt or 0.0) if ends else []
    return case


def build_document(
    runs: Sequence[Run],
    *,
    reference: str | None = None,
    max_divergence: float | None = None,
    thresholds: dict[str, float] | None = None,
    references: Sequence[Reference] = (),
    require_agreement: bool = False,
) -> dict[str, Any]:
    """The report as JSON data. Where no truth is known the engines are compared with each other, unless
    ``reference`` names an engine to measure them against; the events are matched against ``reference``,
    which defaults to :func:`default_reference` of the runs' backends. ``max_divergence`` (metres) makes a
    run whose position quantities (bodies, sliders, joint drift) stray further from their truth a failure,
    and is then the position threshold; ``thresholds`` override the defaults per physical kind
    (``position`` in m, ``angle`` in rad); ``references`` are analytic truths; ``require_agreement`` makes
    disagreement (an engine that misses a truth or departs, or no majority) fail the report."""
    if not runs:
        raise ReportError("no runs to report on")
    names = sorted({r.backend for r in runs})
    explicit = reference is not None
    reference = reference or default_reference(names)
    if reference not in names:
        raise ReportError(f"the reference `{reference}` is not among the runs' backends ({', '.join(names)})")
    limits = {k: dv.DEFAULT_THRESHOLDS[k] for k in KINDS}
    limits.update({k: float(v) for k, v in (thresholds or {}).items() if k in KINDS})
    if max_divergence is not None:
        limits["position"] = float(max_divergence)
    backends = [reference, *[n for n in names if n != reference]] if explicit else names
    rank = {b: i for i, b in enumerate(backends)}
    groups: dict[tuple[str, str], list[Run]] = {}
    for run in runs:
        groups.setdefault((run.scenario, run.variant), []).append(run)
    orders = {s: _variant_order([r for r in runs if r.scenario == s]) for s, _ in groups}
    keys = sorted(groups, key=lambda k: (k[0], orders[k[0]].get(k[1], len(orders[k[0]])), k[1]))
    truths = list(references)
    cases = [_case(sorted(groups[k], key=lambda r: rank[r.backend]), reference, limits, max_divergence, truths,
                   explicit, require_agreement) for k in keys]  # fmt: skip
    all_runs = [r for c in cases for r in c["runs"]]
    top = merge([c["headline"] for c in cases], [c["variant"] for c in cases])
    return {
        "report_format": REPORT_FORMAT,
        "generator": _generator(),
        "reference": reference,
        "comparison": "reference" if explicit else "engines",
        "require_agreement": require_agreement,
        "backends": backends,
        "thresholds": {k: round9(v) for k, v in limits.items()},
        "units": dict(UNITS),
        "max_divergence": max_divergence,
        "passed": top["badge"] == "PASS",
        "headline": top,
        "summary": {
            "cases": len(cases),
            "runs": len(all_runs),
            "ok": sum(r["ok"] for r in all_runs),
            "not_ok": sum(not r["ok"] for r in all_runs),
        },
        "cases": cases,
    }
