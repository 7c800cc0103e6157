"""What each engine is measured against: the truth where one is known, the reference engine elsewhere.

Three kinds of truth, in the order a report shows them:

* **stated**: a value the scenario states in an assertion (``near`` with its ``tol``, or a ``min``/``max``
  bound): every engine's measured value against it, the reference engine's included (:func:`stated_values`);
* **analytic**: a reference solution for one signal over time, supplied by the caller as a
  :class:`Reference` (the physics of the scene: free flight, a slope's acceleration...), and
  **constraint**: what a joint to the environment allows (a body on a slider stays on its line and keeps
  its orientation; a hinge keeps its anchor in place...), from the joint specs in the trace;
* **reference**: where neither exists, the reference engine's own run.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from reports.runs import Run

__all__ = ["Reference", "stated_values"]


@dataclass(frozen=True)
class Reference:
    """An analytic reference for one signal: ``signal`` is a trace series path (``box.pos.z``,
    ``slider.position``), ``values`` its true value at ``times`` (seconds; linearly interpolated between,
    not extrapolated), ``kind`` ``position`` (metres) or ``angle`` (radians) for its threshold, ``source``
    says where it comes from (shown to the reader)."""

    signal: str
    times: Sequence[float]
    values: Sequence[float]
    kind: str
    source: str
    label: str = ""


_RANGE = re.compile(r"in \[([^,\]]+), ([^\]]+)\]")


def _bound(text: str) -> float | None:
    try:
        value = float(text.replace("∞", "inf"))
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _range(expected: Any) -> tuple[float | None, float | None] | None:
    """(lo, hi) of a range verdict's ``expected`` text ("in [lo, hi]", as the runner writes it)."""
    found = _RANGE.fullmatch(str(expected or ""))
    if found is None:
        return None
    return _bound(found.group(1)), _bound(found.group(2))


def _number(v: Any) -> float | None:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) else None


def _r(x: float | None) -> float | None:
    return None if x is None else round(x, 12)


def _cell(data: dict[str, Any]) -> dict[str, Any] | None:
    value, target, tol = _number(data.get("value")), _number(data.get("target")), _number(data.get("tolerance"))
    if value is None:
        return None
    passed = data.get("passed") is True
    if target is not None:
        dev = value - target
        margin = None if tol is None else tol - abs(dev)
        return {"measured": value, "target": target, "tolerance": tol, "lo": None, "hi": None, "deviation": _r(dev),
                "margin": _r(margin), "passed": passed, "time": _number(data.get("time"))}  # fmt: skip
    bounds = _range(data.get("expected"))
    if bounds is None:
        return None
    lo, hi = bounds
    outside = max((lo - value) if lo is not None else 0.0, (value - hi) if hi is not None else 0.0, 0.0)
    margins = ([value - lo] if lo is not None else []) + ([hi - value] if hi is not None else [])
    inside = min(margins) if margins else None
    return {"measured": value, "target": None, "tolerance": None, "lo": lo, "hi": hi, "deviation": _r(outside),
            "margin": _r(inside), "passed": passed, "time": _number(data.get("time"))}  # fmt: skip


def stated_values(runs: Sequence[Run]) -> list[dict[str, Any]]:
    """Every assertion that states a value (a target with a tolerance, or bounds), with each run's
    measured value, its deviation (measured - target; for bounds the distance outside them, 0 inside) and
    margin (tolerance - |deviation|; for bounds the distance to the nearer bound inside them)."""
    out: dict[str, dict[str, Any]] = {}
    for run in runs:
        if run.trace is None:
            continue
        for v in run.trace.verdicts:
            cell = _cell(v.data)
            if cell is None:
                continue
            row = out.setdefault(v.name, {"name": v.name, "kind": v.data.get("kind"), "cells": {}})
            row["cells"][run.backend] = cell
    return list(out.values())
