"""The report's judgement without a privileged engine, on a fake set of four engines' series.

The series are made up (this tests the report's logic, not an engine): a box's position on four engines,
sampled every 0.04 s for 3 s, and, for a body on a slider, its distance from the slider's line. The
threshold is the report's default for positions (reports.divergence.DEFAULT_THRESHOLDS, 1 cm); engines
that "agree" stay a tenth of it apart, engines that "depart" go twice it away, so no verdict sits on the
threshold's edge.
"""

from __future__ import annotations

from itertools import combinations
from typing import Any

import numpy as np
import pytest

from reports import divergence as dv
from reports.consensus import judge
from reports.headline import headline, merge
from reports.quantities import Quantity, measure, truth_wins

ENGINES = ["dart", "mujoco", "ode", "pybullet"]
T = np.round(np.arange(0, 76) * 0.04, 9)
LIMIT = dv.DEFAULT_THRESHOLDS["position"]
NEAR = LIMIT / 10  # how far engines that agree are apart
FAR = 2 * LIMIT  # how far an engine that departs goes


def _path(offset: float = 0.0, after: float = 0.0, along: int = 0) -> np.ndarray:
    """A box falling from 2 m, moved by ``offset`` along axis ``along`` from ``after`` seconds on."""
    p = np.column_stack([np.ones_like(T), np.zeros_like(T), 2.0 - 0.5 * 9.81 * np.minimum(T, 0.6) ** 2])
    p[T >= after - 1e-9, along] += offset
    return p


def _among(paths: dict[str, np.ndarray], label: str = "box position") -> dict[str, Any]:
    pairs = {(a, b): (T, np.linalg.norm(paths[a] - paths[b], axis=1)) for a, b in combinations(list(paths), 2)}
    q = Quantity(label.replace(" ", ":"), label, "position", {"kind": "engines"}, {}, pairs)
    return measure(q, list(paths), list(paths), LIMIT)


def _runs(names: list[str], failed: int = 0) -> list[dict[str, Any]]:
    return [{"backend": b, "status": "passed", "label": "passed", "end_time": float(T[-1]),
             "assertions": {"total": 3, "passed": 3 - failed, "failed": failed}} for b in names]  # fmt: skip


def test_three_agree_and_the_one_that_departs_is_named_with_when_and_how_much() -> None:
    paths = {"dart": _path(), "mujoco": _path(NEAR, 0.5), "ode": _path(FAR, 1.08, along=2), "pybullet": _path(-NEAR)}
    q = _among(paths)
    verdict = q["agreement"]
    assert verdict["groups"] == [["dart", "mujoco", "pybullet"], ["ode"]]
    assert verdict["majority"] == ["dart", "mujoco", "pybullet"] and verdict["no_majority_from"] is None
    (d,) = verdict["departures"]
    # ode is FAR from dart, and FAR ± NEAR from the other two (their offsets are along x, ode's along z)
    assert d["backend"] == "ode" and d["from"] == 1.08 and d["until"] is None
    assert d["max"] == pytest.approx(np.hypot(FAR, NEAR), abs=1e-9)  # the report rounds to 1e-9
    assert q["diverging"] == ["ode"] and q["first_over"] == 1.08
    assert q["deviation"]["dart"]["first_over"] is None and q["deviation"]["ode"]["first_over"] == 1.08
    h = headline(_runs(ENGINES), [q])
    assert h["badge"] == "PASS"  # the assertions pass: a departure alone never fails the badge
    assert h["text"] == "assertions pass · ode departs from the other 3 from 1.08 s by up to 2 cm (box position)"
    assert h["agreement"]["backends"] == ["ode"] and not h["agreement"]["agrees"]
    strict = headline(_runs(ENGINES), [q], required=True)  # --require-agreement: disagreement fails, and says so
    assert strict["badge"] == "FAIL" and strict["text"].endswith(" · agreement required")


def test_two_against_two_is_no_majority_and_nobody_is_named() -> None:
    paths = {"dart": _path(), "mujoco": _path(NEAR), "ode": _path(FAR, 1.0), "pybullet": _path(FAR + NEAR, 1.0)}
    q = _among(paths)
    verdict = q["agreement"]
    assert verdict["groups"] == [["dart", "mujoco"], ["ode", "pybullet"]] and verdict["majority"] is None
    assert verdict["no_majority_from"] == 1.0 and verdict["departures"] == [] and q["diverging"] == []
    h = headline(_runs(ENGINES), [q])
    assert h["badge"] == "PASS" and h["agreement"]["backends"] == []
    assert h["text"] == "assertions pass · no majority (box position from 1 s: dart, mujoco | ode, pybullet)"


def test_two_engines_that_disagree_name_neither() -> None:
    """No engine is marked only because it disagrees with one other engine."""
    q = _among({"ode": _path(), "pybullet": _path(FAR, 1.0)})
    assert q["agreement"]["majority"] is None and q["diverging"] == []
    assert q["agreement"]["groups"] == [["ode"], ["pybullet"]]


def test_all_agree() -> None:
    q = _among({b: _path(k * NEAR / 2) for k, b in enumerate(ENGINES)})  # at most 1.5 NEAR apart
    assert q["agreement"]["groups"] == [ENGINES] and q["diverging"] == [] and q["agreement"]["departures"] == []
    h = headline(_runs(ENGINES), [q])
    assert h["badge"] == "PASS" and h["agreement"]["agrees"] and h["text"] == "assertions pass · 4 engines agree"
    assert merge([h, h], ["a", "b"])["text"] == "assertions pass · 4 engines agree"


def test_a_failed_assertion_is_what_fails_the_badge() -> None:
    q = _among({b: _path() for b in ENGINES})
    h = headline(_runs(ENGINES, failed=1), [q])
    assert h["badge"] == "FAIL" and h["text"] == "4 assertions fail · 4 engines agree"


def test_a_known_truth_wins_over_a_majority_that_misses_it() -> None:
    """A door on a slider may only move along its line: three engines let it sag 2 cm (they agree with each
    other), one holds it on the line. The box resting on the door follows it, so on the box's position (no
    truth known) the one engine right about the door departs from the three. The truth wins: the three are
    named, as missing it; the one is not."""
    sag = {b: np.full(T.size, 0.0 if b == "ode" else FAR) for b in ENGINES}
    door = measure(Quantity("door:joint-distance", "door off the slider's line", "position",
                            {"kind": "constraint", "source": "slider"}, {b: (T, e) for b, e in sag.items()}),
                   ENGINES, ENGINES, LIMIT)  # fmt: skip
    box = _among({b: _path(0.0 if b == "ode" else -FAR, 0.0, along=2) for b in ENGINES})
    assert door["diverging"] == ["dart", "mujoco", "pybullet"]
    assert box["agreement"]["departures"][0]["backend"] == "ode" and box["diverging"] == ["ode"]  # before the truth
    truth_wins([door, box])
    assert box["diverging"] == [] and box["first_over"] is None and box["agreement"]["departures"][0]["overruled"]
    h = headline(_runs(ENGINES), [door, box])
    assert h["agreement"]["backends"] == ["dart", "mujoco", "pybullet"] and h["agreement"]["departures"] == []
    assert h["badge"] == "PASS"
    assert h["text"] == (
        "assertions pass · dart misses the truth by up to 2 cm (door off the slider's line) from 0 s · mujoco misses "
        "the truth by up to 2 cm (door off the slider's line) from 0 s · pybullet misses the truth by up to 2 cm "
        "(door off the slider's line) from 0 s · ode meets the truth that dart, mujoco, pybullet miss (it departs "
        "from them on box position)"
    )


def test_a_stated_value_is_a_truth_too() -> None:
    box = _among({b: _path(0.0 if b == "ode" else -FAR, 0.0, along=2) for b in ENGINES})
    cell = {"passed": True}
    stated = [{"name": "box-rests", "cells": {b: cell if b == "ode" else {"passed": False} for b in ENGINES}}]
    truth_wins([box], stated)
    assert box["diverging"] == []


def test_overlapping_agreement_is_no_majority() -> None:
    """a ~ b and b ~ c but a !~ c: two sets of two agree, so neither is the majority of three."""
    t = T[:3]
    near, far = (t, np.full(3, NEAR)), (t, np.full(3, FAR))
    verdict = judge(["a", "b", "c"], {("a", "b"): near, ("b", "c"): near, ("a", "c"): far}, LIMIT)
    assert verdict.majority is None and verdict.departures == [] and verdict.no_majority_from == 0.0
