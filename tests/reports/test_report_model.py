"""The comparison document's judgement, on small inputs: stated values, headline words, moments, charts."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import pytest

from reports.charts import render
from reports.charts.specs import Rule, Series, line_chart
from reports.charts.style import COLORS, DASHES, MARKERS, look
from reports.headline import headline, merge
from reports.moments import key_moments
from reports.truth import _cell

SVG = "{http://www.w3.org/2000/svg}"


def test_a_stated_target_gives_the_signed_deviation_and_the_margin() -> None:
    cell = _cell({"value": 0.19181926548480988, "target": 0.2, "tolerance": 0.01, "passed": True, "time": 3.0})
    assert cell is not None
    assert cell["deviation"] == pytest.approx(-0.00818073451519) and cell["margin"] == pytest.approx(0.00181926548481)


def test_a_stated_range_gives_the_distance_outside_and_the_margin_inside() -> None:
    inside = _cell({"value": 1.3e-7, "target": None, "expected": "in [-inf, 0.01]", "passed": True, "time": 6.0})
    assert inside is not None and inside["deviation"] == 0.0 and inside["hi"] == 0.01 and inside["lo"] is None
    assert inside["margin"] == pytest.approx(0.01 - 1.3e-7)
    outside = _cell({"value": 1.5, "target": None, "expected": "in [0.5, 1]", "passed": False, "time": 2.0})
    assert outside is not None and outside["deviation"] == pytest.approx(0.5)
    assert outside["margin"] == pytest.approx(-0.5)
    assert _cell({"value": None, "expected": "held over the window"}) is None  # a window states no value


def _run(backend: str, failed: int = 0, status: str = "passed") -> dict[str, Any]:
    return {"backend": backend, "status": status, "label": "crashed (signal 11)" if status == "crashed" else status,
            "assertions": {"total": 9, "passed": 9 - failed, "failed": failed},
            "end_time": None if status == "crashed" else 6.0}  # fmt: skip


def _q(label: str, diverging: list[str], first: float | None) -> dict[str, Any]:
    """A quantity against a known truth (a joint's constraint): 1 cm threshold, 2 cm off where it diverges."""
    return {"id": label, "label": label, "unit": "m", "threshold": 0.01, "truth": {"kind": "constraint"},
            "diverging": diverging, "first_over": first,
            "deviation": {b: {"max": 0.02, "first_over": first} for b in diverging}}  # fmt: skip


def test_the_headline_says_assertions_and_agreement_apart() -> None:
    """The badge is the assertions' (and the runs' finishing); agreement is said in words beside it."""
    good = headline([_run("ode"), _run("dart")], [_q("box position", [], None)])
    assert good["badge"] == "PASS" and good["text"] == "assertions pass · 2 engines agree"
    drift = headline([_run("ode"), _run("dart")], [_q("a", ["dart"], 1.08), _q("b", ["dart"], 1.04), _q("c", [], None)])
    assert drift["badge"] == "PASS"  # an engine that misses a truth is named, not failed (without --require-agreement)
    assert drift["text"] == "assertions pass · dart misses the truth by up to 2 cm (b and 1 more quantity) from 1.04 s"
    assert drift["assertions"]["passed"] and not drift["agreement"]["agrees"]
    assert drift["agreement"]["backends"] == ["dart"]
    broken = headline([_run("ode", failed=1), _run("crash", status="crashed")], [])
    assert broken["badge"] == "FAIL"
    assert broken["text"] == "1 assertion fails · 1 run crashed (signal 11) · no quantity compared"
    both = merge([good, drift, broken], ["good", "drift", "broken"])
    assert both["badge"] == "FAIL"
    assert both["text"] == ("1 assertion fails · 1 run crashed (signal 11) · dart misses the truth in 1 of 3 cases "
                            "by up to 2 cm (b and 1 more quantity) from 1.04 s")


def test_moments_are_the_start_failures_close_calls_first_divergence_and_end() -> None:
    case = {
        "verdicts": {"assertions": ["rests", "lands"], "cells": {
            "rests": {"ode": {"passed": True, "time": 3.0}, "dart": {"passed": False, "time": 3.0}},
            "lands": {"ode": {"passed": True, "time": 1.0}, "dart": {"passed": True, "time": 1.0}}}},
        "stated": [{"name": "lands", "cells": {
            "ode": {"passed": True, "tolerance": 0.021, "deviation": 0.02, "time": 1.0},
            "dart": {"passed": True, "tolerance": 0.021, "deviation": 0.001, "time": 1.0}}}],
        "quantities": [{"label": "box position", "first_over": 1.04, "diverging": ["dart"],
                        "deviation": {"dart": {"first_over": 1.04}}}],
    }  # fmt: skip
    moments = key_moments(case, 6.0, 0.04)
    assert [m["t"] for m in moments] == [0.0, 1.0, 1.04, 3.0, 6.0]
    assert moments[1]["reasons"] == ["lands close to its tolerance (ode)"]
    assert moments[2]["reasons"] == ["first divergence: box position (dart)"]
    assert moments[3]["reasons"] == ["rests fails (dart)"]
    # within half a step, moments merge
    assert [m["t"] for m in key_moments(case, 3.01, 0.04)] == [0.0, 1.0, 1.04, 3.0]


def test_every_backend_gets_its_own_colour_dash_and_marker() -> None:
    looks = [look(i) for i in range(len(COLORS))]
    assert len({lk.color for lk in looks}) == len({lk.dash for lk in looks}) == len({lk.marker for lk in looks}) == 7
    assert "#F0E442" not in COLORS  # Okabe-Ito's yellow: invisible on white
    assert len(DASHES) == len(MARKERS) == len(COLORS)


def test_a_line_chart_renders_the_same_bytes_with_units_on_its_axes() -> None:
    series = [Series("ode", [0.0, 0.5, 1.0], [0.0, 0.004, None], look(0)),
              Series("dart", [0.0, 0.5, 1.0], [0.0, 0.012, 0.02], look(1))]  # fmt: skip
    spec = line_chart("door: deviation", series, y_title="deviation (m)", rules=[Rule(0.01, "threshold 0.01 m")])
    svg = render.svg(spec)
    assert svg == render.svg(spec)  # deterministic, whatever was drawn before in this process
    root = ET.fromstring(svg)
    texts = {t.text for t in root.iter(f"{SVG}text")}
    assert {"t (s)", "deviation (m)", "threshold 0.01 m", "ode", "dart", "door: deviation"} <= texts
    lines = [g for g in root.iter(f"{SVG}g") if g.get("class", "").startswith("mark-line role-mark")]
    strokes = {p.get("stroke") for g in lines for p in g.iter(f"{SVG}path")}
    assert strokes == {look(0).color, look(1).color}
    dashes = {p.get("stroke-dasharray") for g in lines for p in g.iter(f"{SVG}path")}
    assert "7,3" in dashes  # the second backend's dash
    assert render.png(spec)[:8] == b"\x89PNG\r\n\x1a\n"
