"""Vega-Lite specs for every chart in the project: lines over time, event timelines, bands.

Each builder returns a plain Vega-Lite dict (data inline, keys in a fixed order), so the same data give
the same spec and vl-convert the same image. Interactive charts (``interactive=True``) zoom and pan
(drag, wheel; double-click resets), show the values under the pointer (the nearest sample of any
series) and hide or show a series by clicking its legend entry. Series are distinguished by colour,
dash and marker (:mod:`reports.charts.style`); every axis has a title with its unit.

Series data are written column-wise (one array of times and one of values per series, expanded by a
``flatten`` transform), which keeps a page's data about three times smaller than one object per sample.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from reports.charts.style import Look

__all__ = ["SCHEMA", "Rule", "Series", "band_chart", "line_chart", "stack", "timeline_chart"]

SCHEMA = "https://vega.github.io/schema/vega-lite/v6.json"
FONT = "system-ui, -apple-system, Segoe UI, Helvetica, Arial, sans-serif"
MARKERS_PER_SERIES = 10
DIGITS = 6  # significant digits of plotted values (the report's JSON keeps the traces' resolution)


@dataclass(frozen=True)
class Series:
    """One line: ``label`` (a backend), x values and y values (None: a gap)."""

    label: str
    x: Sequence[float]
    y: Sequence[float | None]
    look: Look


@dataclass(frozen=True)
class Rule:
    """A labelled horizontal line (a threshold, a tolerance) or, with ``vertical``, a marked time."""

    value: float
    label: str
    vertical: bool = False


@dataclass
class _Columns:
    rows: list[dict[str, Any]] = field(default_factory=list)


def _num(v: float | None) -> float | None:
    if v is None or not math.isfinite(v):
        return None
    return float(f"{v:.{DIGITS}g}")


def _config() -> dict[str, Any]:
    return {
        "font": FONT,
        "axis": {"labelFontSize": 11, "titleFontSize": 12, "titleFontWeight": "normal", "grid": True,
                 "gridColor": "#e6e8eb"},
        "legend": {"labelFontSize": 11, "titleFontSize": 11, "orient": "top", "symbolStrokeWidth": 2,
                   "symbolSize": 90, "labelLimit": 260},
        "title": {"fontSize": 13, "anchor": "start", "fontWeight": 600, "offset": 6, "subtitleFontSize": 11,
                  "subtitleColor": "#5b6570"},
        "view": {"stroke": "#c9ced4"},
        "background": "#ffffff",
    }  # fmt: skip


def _series_data(series: Sequence[Series]) -> list[dict[str, Any]]:
    out = []
    for s in series:
        n = len(s.x)
        every = max(1, n // MARKERS_PER_SERIES)
        offset = (hash_label(s.label) % every) if every > 1 else 0
        marks = [1 if (k - offset) % every == 0 else 0 for k in range(n)]
        out.append({"s": s.label, "x": [_num(float(v)) for v in s.x], "y": [_num(v) for v in s.y], "m": marks})
    return out


def hash_label(label: str) -> int:
    """A stable small number per label (markers of different series fall on different samples)."""
    return sum((i + 1) * ord(c) for i, c in enumerate(label))


def _scales(series: Sequence[Series]) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    labels = [s.label for s in series]
    color = {"domain": labels, "range": [s.look.color for s in series]}
    dash = {"domain": labels, "range": [list(s.look.dash) for s in series]}
    shape = {"domain": labels, "range": [s.look.marker for s in series]}
    return color, dash, shape


def line_chart(
    title: str,
    series: Sequence[Series],
    *,
    x_title: str = "t (s)",
    y_title: str,
    rules: Sequence[Rule] = (),
    subtitle: str = "",
    width: int = 520,
    height: int = 220,
    interactive: bool = True,
    legend_title: str = "backend",
) -> dict[str, Any]:
    """Lines of ``series`` against time with labelled ``rules``; ``y_title`` names the quantity and unit."""
    color, dash, shape = _scales(series)
    legend = {"title": legend_title}
    x = {"field": "x", "type": "quantitative", "title": x_title, "scale": {"zero": False, "nice": False}}
    y = {"field": "y", "type": "quantitative", "title": y_title, "scale": {"zero": False}}
    by = {"field": "s", "type": "nominal"}
    line: dict[str, Any] = {
        "mark": {"type": "line", "strokeWidth": 1.8, "clip": True, "interpolate": "linear"},
        "encoding": {
            "x": x, "y": y,
            "color": {**by, "scale": color, "legend": legend},
            "strokeDash": {**by, "scale": dash, "legend": legend},
        },
    }  # fmt: skip
    markers: dict[str, Any] = {
        "transform": [{"filter": "datum.m == 1"}],
        "mark": {"type": "point", "filled": True, "size": 42, "clip": True},
        "encoding": {"x": x, "y": y, "color": {**by, "scale": color, "legend": legend},
                     "shape": {**by, "scale": shape, "legend": legend}},
    }  # fmt: skip
    layers = [line, markers]
    if interactive:
        pick = {"name": "pick", "select": {"type": "point", "fields": ["s"]}, "bind": "legend"}
        zoom = {"name": "zoom", "select": {"type": "interval", "encodings": ["x", "y"]}, "bind": "scales"}
        line["params"] = [pick, zoom]
        fade = {"condition": {"param": "pick", "value": 1}, "value": 0.12}
        line["encoding"]["opacity"] = fade
        markers["encoding"]["opacity"] = fade
        # no "nearest" (its Voronoi cells lose the series name in the tooltip): wide, invisible points instead
        hover = {"name": "hover", "select": {"type": "point", "on": "pointerover", "clear": "pointerout"}}
        layers.append({
            "params": [hover],
            "mark": {"type": "point", "size": 160, "filled": True, "clip": True, "color": "#1d232b"},
            "encoding": {
                "x": x, "y": y,
                "opacity": {"condition": {"param": "hover", "empty": False, "value": 0.35}, "value": 0},
                "tooltip": [{"field": "s", "title": legend_title}, {"field": "x", "title": x_title, "format": ".4~g"},
                            {"field": "y", "title": y_title, "format": ".5~g"}],
            },
        })  # fmt: skip
    for rule in rules:
        layers.append(_rule_layer(rule, x if rule.vertical else y))
    return {
        "$schema": SCHEMA,
        "title": {"text": title, **({"subtitle": subtitle} if subtitle else {})},
        "width": width,
        "height": height,
        "data": {"values": _series_data(series)},
        "transform": [{"flatten": ["x", "y", "m"]}, {"filter": "isValid(datum.y)"}],
        "layer": layers,
        "config": _config(),
    }


def _rule_layer(rule: Rule, axis: dict[str, Any]) -> dict[str, Any]:
    channel = "x" if rule.vertical else "y"
    text: dict[str, Any] = {"type": "text", "align": "right" if not rule.vertical else "left", "baseline": "top",
                            "fontSize": 10, "color": "#4d5560", "dy": 2}  # fmt: skip
    enc_text: dict[str, Any] = {channel: {**axis, "field": "v"}, "text": {"field": "label"}}
    if rule.vertical:
        text.update({"dx": 3, "y": 0, "baseline": "top"})
    else:
        text.update({"x": "width"})
    return {
        "data": {"values": [{"v": _num(rule.value), "label": rule.label}]},
        "layer": [
            {"mark": {"type": "rule", "strokeDash": [3, 3], "color": "#6b7580", "strokeWidth": 1.2},
             "encoding": {channel: {**axis, "field": "v"}}},
            {"mark": text, "encoding": enc_text},
        ],
    }  # fmt: skip


def band_chart(
    title: str,
    x: Sequence[float],
    expected: Sequence[float | None],
    low: Sequence[float | None],
    high: Sequence[float | None],
    got: Sequence[float | None],
    *,
    y_title: str,
    looks: tuple[Look, Look],
    labels: tuple[str, str] = ("baseline", "this run"),
    rules: Sequence[Rule] = (),
    width: int = 640,
    height: int = 240,
) -> dict[str, Any]:
    """A reference curve with its tolerance band and a second curve (a baseline and a run)."""
    base = line_chart(title, [Series(labels[0], x, expected, looks[0]), Series(labels[1], x, got, looks[1])],
                      y_title=y_title, rules=rules, width=width, height=height, interactive=False,
                      legend_title="curve")  # fmt: skip
    band = {
        "data": {"values": [{"x": [_num(float(v)) for v in x], "lo": [_num(v) for v in low],
                             "hi": [_num(v) for v in high]}]},
        "transform": [{"flatten": ["x", "lo", "hi"]}, {"filter": "isValid(datum.lo) && isValid(datum.hi)"}],
        "mark": {"type": "area", "opacity": 0.18, "color": looks[0].color},
        "encoding": {"x": {"field": "x", "type": "quantitative"}, "y": {"field": "lo", "type": "quantitative"},
                     "y2": {"field": "hi"}},
    }  # fmt: skip
    base["layer"] = [band, *base["layer"]]
    return base


def timeline_chart(
    title: str,
    rows: Sequence[tuple[str, Look, Sequence[tuple[float, str]]]],
    names: Sequence[str],
    t_end: float,
    *,
    x_title: str = "t (s)",
    width: int = 760,
    interactive: bool = True,
    rules: Sequence[Rule] = (),
) -> dict[str, Any]:
    """One row per run (label, look, [(t, event name)]): a mark per occurrence, shaped by event name."""
    values = [{"run": label, "t": _num(t), "event": name} for label, _, items in rows for t, name in items]
    shapes = ["circle", "square", "diamond", "triangle-up", "cross", "triangle-down", "wedge", "stroke"]
    labels = [label for label, _, _ in rows]
    layer: dict[str, Any] = {
        "mark": {"type": "point", "filled": True, "size": 70, "opacity": 0.85},
        "encoding": {
            "x": {"field": "t", "type": "quantitative", "title": x_title, "scale": {"domain": [0, _num(t_end)]}},
            "y": {"field": "run", "type": "nominal", "title": None, "sort": labels},
            "color": {"field": "run", "type": "nominal", "legend": None,
                      "scale": {"domain": labels, "range": [lk.color for _, lk, _ in rows]}},
            "shape": {"field": "event", "type": "nominal", "title": "event",
                      "scale": {"domain": list(names), "range": [shapes[i % len(shapes)] for i in range(len(names))]}},
        },
    }  # fmt: skip
    if interactive:
        layer["encoding"]["tooltip"] = [{"field": "run", "title": "backend"}, {"field": "event"},
                                        {"field": "t", "title": x_title, "format": ".4~g"}]  # fmt: skip
        layer["params"] = [{"name": "zoom", "select": {"type": "interval", "encodings": ["x"]}, "bind": "scales"}]
    layers = [layer] + [_rule_layer(r, {"type": "quantitative"}) for r in rules]
    return {
        "$schema": SCHEMA,
        "title": {"text": title},
        "width": width,
        "height": {"step": 26},
        "data": {"values": values},
        "layer": layers,
        "config": _config(),
    }


def stack(title: str, charts: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Charts one above the other under one title (each keeps its own axes and legend)."""
    parts = [{k: v for k, v in c.items() if k not in ("$schema", "config")} for c in charts]
    return {"$schema": SCHEMA, "title": {"text": title}, "vconcat": parts, "spacing": 28,
            "resolve": {"scale": {"color": "independent", "strokeDash": "independent", "shape": "independent"}},
            "config": _config()}  # fmt: skip
