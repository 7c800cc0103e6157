"""The charts of a case, as Vega-Lite specs (reports.charts) with the ids the page draws them under.

Deviation charts come first, one per quantity, against the quantity's truth and with its threshold
drawn; trajectories (one per body and axis, one per joint) and the event and sound timelines follow.
Long series are thinned to at most :data:`MAX_POINTS` samples for the page (report.json keeps them all).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from reports.charts.specs import Rule, Series, line_chart, timeline_chart
from reports.charts.style import Look

__all__ = ["MAX_POINTS", "deviation_charts", "event_charts", "quantity_axis", "trajectory_charts", "truth_name"]

MAX_POINTS = 400
WIDTH = 560


def _thin(x: Sequence[float], y: Sequence[float | None]) -> tuple[list[float], list[float | None]]:
    step = max(1, -(-len(x) // MAX_POINTS))
    if step == 1:
        return list(x), list(y)
    keep = list(range(0, len(x), step))
    if keep[-1] != len(x) - 1:
        keep.append(len(x) - 1)
    return [x[k] for k in keep], [y[k] for k in keep]


def truth_name(q: dict[str, Any]) -> str:
    truth = q["truth"]
    if truth["kind"] == "reference":
        return f"{truth['backend']}'s run"
    if truth["kind"] == "engines":
        return "the engines it is judged with"
    if truth["kind"] == "constraint":
        return "the joint's constraint (0)"
    return "the analytic reference"


def quantity_axis(q: dict[str, Any]) -> str:
    return f"deviation ({q['unit']})"


def deviation_charts(case: dict[str, Any], looks: dict[str, Look], prefix: str) -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for k, q in enumerate(case["quantities"]):
        series = []
        for backend, s in q["series"].items():
            x, y = _thin(s["t"], s["deviation"])
            series.append(Series(backend, x, y, looks[backend]))
        if not series:
            continue
        rule = Rule(q["threshold"], f"threshold {q['threshold']:.3g} {q['unit']}")
        title = f"{q['label']}: deviation from {truth_name(q)}"
        out[f"{prefix}-dev-{k}"] = line_chart(title, series, y_title=quantity_axis(q), rules=[rule], width=WIDTH,
                                              height=190)  # fmt: skip
    return out


def trajectory_charts(case: dict[str, Any], looks: dict[str, Look], prefix: str,
                      joint_kinds: dict[str, str]) -> dict[str, dict[str, Any]]:  # fmt: skip
    out: dict[str, dict[str, Any]] = {}
    runs = {b: t for b, t in case["trajectories"].items() if t}
    bodies = list(dict.fromkeys(b for t in runs.values() for b in t["bodies"]))
    for body in bodies:
        for axis in ("x", "y", "z"):
            series = []
            for backend, t in runs.items():
                if body in t["bodies"]:
                    x, y = _thin(t["t"], t["bodies"][body][axis])
                    series.append(Series(backend, x, y, looks[backend]))
            out[f"{prefix}-traj-{body}-{axis}"] = line_chart(f"{body}.pos.{axis}", series, y_title=f"{body}.pos.{axis}"
                                                             " (m)", width=WIDTH, height=170)  # fmt: skip
    joints = list(dict.fromkeys(j for t in runs.values() for j in t["joints"]))
    for joint in joints:
        series = []
        for backend, t in runs.items():
            if joint in t["joints"]:
                x, y = _thin(t["t"], t["joints"][joint])
                series.append(Series(backend, x, y, looks[backend]))
        unit = {"slider": "position (m)", "hinge": "angle (rad)"}.get(joint_kinds.get(joint, ""), "position")
        out[f"{prefix}-joint-{joint}"] = line_chart(f"{joint} {unit.split(' ')[0]}", series,
                                                    y_title=f"{joint} {unit}", width=WIDTH, height=170)  # fmt: skip
    return out


def event_charts(case: dict[str, Any], looks: dict[str, Look], prefix: str, end: float) -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    ev = case["events"]
    rows = [(b, looks[b], [(e["t"], e["name"]) for e in items]) for b, items in ev["timelines"].items()]
    if any(items for _, _, items in rows):
        out[f"{prefix}-events"] = timeline_chart("events", rows, ev["names"], end, width=1000)
    starts = [(b, looks[b], [(s["t"], s["name"]) for s in items if s["action"] == "start"])
              for b, items in case["sounds"].items()]  # fmt: skip
    names = list(dict.fromkeys(n for _, _, items in starts for _, n in items))
    if names:
        out[f"{prefix}-sounds"] = timeline_chart("sound starts", starts, names, end, width=1000)
    return out
