"""The plot of the signal where a run first left its golden file, as an SVG (the project's one charting path,
reports.charts: Vega-Lite specs rendered by vl-convert, the same bytes for the same data).

A sampled signal is drawn as the golden's curve with its tolerance band, the run's curve, and a dashed line
at the first divergence; an event or sound divergence as two timelines (golden above, run below).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from reports.charts import render
from reports.charts.specs import Rule, band_chart, timeline_chart
from reports.charts.style import look
from runner.ci.golden import Tolerances, _num
from runner.ci.golden_compare import Comparison, series

__all__ = ["signal_svg", "timeline_svg", "unit_of", "write_divergence_plot"]

GOLDEN, RUN = look(0), look(1)

_UNITS = {"pos": "m", "vel": "m/s", "angvel": "rad/s", "quat": "unit quaternion component", "velocity": "joint speed:"
          " m/s for a slider, rad/s for a hinge", "position": "joint position: m for a slider, rad for a hinge",
          "motor_force": "N for a slider, N·m for a hinge"}  # fmt: skip


def unit_of(kind: str, field: str) -> str:
    """The unit of a golden signal's field (``pos.z`` -> m), for the axis title."""
    if kind == "var":
        return "value"
    return _UNITS.get(field.split(".")[0], "value")


def write_divergence_plot(comparison: Comparison, tolerances: Tolerances, path: Path) -> Path | None:
    """Plot the first divergence of ``comparison`` into ``path``; None when there is nothing to plot."""
    first = comparison.first
    if first is None:
        return None
    exp, got = comparison.expected, comparison.got
    title = f"{exp.label()}: {first.kind} {first.name} {first.field}"
    if first.kind in ("event", "sound"):
        pick = (lambda r: r.events) if first.kind == "event" else (lambda r: r.sounds)
        svg = timeline_svg(title, pick(exp), pick(got), first.time)
    else:
        e = series(exp, first.kind, first.name, first.field)
        g = series(got, first.kind, first.name, first.field)
        if e is None or g is None:
            return None
        n = min(len(e), len(g))
        fld = "state" if first.kind == "var" else first.field.split(".")[0]
        atol, rtol = tolerances.lookup(first.name, fld)
        if first.field.startswith("quat."):  # the sign the comparison chose
            g = _aligned_quat_component(comparison, first.name, first.field, g)
        y_title = f"{first.name}.{first.field} ({unit_of(first.kind, first.field)})"
        svg = signal_svg(title, exp.times[:n], e[:n], g[:n], atol + rtol * np.abs(e[:n]), first.time, y_title)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(svg, encoding="utf-8")
    return path


def _aligned_quat_component(comparison: Comparison, body: str, label: str, g: np.ndarray) -> np.ndarray:
    e4 = comparison.expected.bodies[body][:, 3:7]
    g4 = comparison.got.bodies[body][:, 3:7]
    n = min(len(e4), len(g4))
    flip = np.nansum(e4[:n] * g4[:n], axis=1) < 0
    out = np.array(g[:n], float)
    out[flip] = -out[flip]
    return out


def _values(a: np.ndarray) -> list[float | None]:
    return [float(v) if np.isfinite(v) else None for v in np.asarray(a, float)]


def signal_svg(title: str, t: np.ndarray, expected: np.ndarray, got: np.ndarray, bound: np.ndarray, first: float,
               y_title: str = "value") -> str:  # fmt: skip
    """The golden curve with its tolerance band, the run's curve, and the first divergence."""
    spec = band_chart(
        title, [float(x) for x in t], _values(expected), _values(expected - bound), _values(expected + bound),
        _values(got), y_title=y_title, looks=(GOLDEN, RUN), labels=("baseline (band: tolerance)", "this run"),
        rules=[Rule(first, f"first divergence {_num(first)} s", vertical=True)],
    )  # fmt: skip
    return render.svg(spec)


def timeline_svg(title: str, expected: Sequence[tuple[float, str, str]], got: Sequence[tuple[float, str, str]],
                 first: float) -> str:  # fmt: skip
    """Two rows of event marks, the golden's above the run's, with the first divergence."""
    rows = [("baseline", GOLDEN, [(t, n) for t, n, _ in expected]), ("this run", RUN, [(t, n) for t, n, _ in got])]
    names = list(dict.fromkeys(n for _, _, items in rows for _, n in items))
    end = max([t for _, _, items in rows for t, _ in items] + [first]) * 1.05 or 1.0
    spec = timeline_chart(title, rows, names, end, interactive=False, width=640,
                          rules=[Rule(first, f"first divergence {_num(first)} s", vertical=True)])  # fmt: skip
    return render.svg(spec)
