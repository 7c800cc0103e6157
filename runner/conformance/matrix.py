"""The conformance matrix: every check of every case on every backend, against the analytic value and
against the reference backend (``ode``), as plain JSON-ready data.

A cell holds the raw measured value, the analytic target and the tolerance the case states for that
backend, the error ``measured - target`` and the difference ``measured - reference's measured``; its
status is the runner's verdict (pass / fail), or ``not run`` when the case did not complete on the backend
(crash, time-out, engine failure, unsupported feature). The matrix passes only when every case passed on
every backend.
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Mapping, Sequence
from typing import Any

from backends.registry import REFERENCE_BACKEND
from runner.conformance.cases import Case
from runner.conformance.pool import BackendRun
from runner.version import tool_version

REFERENCE = REFERENCE_BACKEND
SCHEMA = "physics-scenarios/conformance-matrix/1"


def _diff(a: Any, b: Any) -> float | None:
    if isinstance(a, int | float) and isinstance(b, int | float) and math.isfinite(a) and math.isfinite(b):
        return float(a) - float(b)
    return None


def _cell(check: dict[str, Any] | None, reference: dict[str, Any] | None) -> dict[str, Any]:
    if check is None:
        return {"status": "not run"}
    return {
        "status": "pass" if check["passed"] else "fail",
        "measured": check.get("measured"),
        "target": check.get("target"),
        "tol": check.get("tol"),
        "error": _diff(check.get("measured"), check.get("target")),
        "vs_reference": _diff(check.get("measured"), reference.get("measured")) if reference else None,
        "measured_text": check.get("measured_text", ""),
        "expected_text": check.get("expected_text", ""),
        "time": check.get("time"),
        "message": check.get("message", ""),
    }


def _checks_by_index(result: Mapping[str, Any] | None, count: int) -> list[dict[str, Any] | None]:
    checks = list(result.get("checks") or []) if result else []
    return checks + [None] * (count - len(checks)) if len(checks) <= count else checks[:count]


def build_matrix(
    cases: Sequence[Case],
    runs: Mapping[str, BackendRun],
    suite: str,
    date: _dt.date | None = None,
) -> dict[str, Any]:
    """The matrix of ``cases`` x ``runs`` (backends in the order given)."""
    backends = list(runs)
    reference = REFERENCE if REFERENCE in runs else None
    out_cases: list[dict[str, Any]] = []
    for case in cases:
        results = {b: runs[b].results.get(case.id) for b in backends}
        per_backend = {b: _checks_by_index(results[b], len(case.checks)) for b in backends}
        checks = []
        for i, check in enumerate(case.checks):
            ref = per_backend[reference][i] if reference else None
            cells = {b: _cell(per_backend[b][i], ref if b != reference else None) for b in backends}
            checks.append(
                {
                    "name": check.name,
                    "kind": check.kind,
                    "measure": check.measure,
                    "expected": check.expected,
                    "tolerance": check.tolerance,
                    "description": check.description,
                    "cells": cells,
                }
            )
        out_cases.append(
            {
                "id": case.id,
                "file": case.file,
                "variant": case.variant,
                "scenario": case.scenario,
                "semantic": case.semantic,
                "description": case.variant_description,
                "runs": {
                    b: {
                        "status": (results[b] or {}).get("status", "not run"),
                        "message": (results[b] or {}).get("message", ""),
                        "wall_seconds": round(float((results[b] or {}).get("wall_seconds", 0.0)), 3),
                    }
                    for b in backends
                },
                "checks": checks,
            }
        )
    return {
        "schema": SCHEMA,
        "suite": suite,
        "date": (date or _dt.date.today()).isoformat(),
        "tool_version": tool_version(),
        "reference": reference,
        "backends": [
            {
                "name": b,
                "engine_version": runs[b].engine_version,
                "wall_seconds": round(runs[b].wall_seconds, 2),
                "passed": sum(c["runs"][b]["status"] == "passed" for c in out_cases),
                "cases": len(out_cases),
            }
            for b in backends
        ],
        "cases": out_cases,
        "passed": bool(out_cases) and all(r["status"] == "passed" for c in out_cases for r in c["runs"].values()),
    }


def run_statuses(matrix: Mapping[str, Any]) -> set[str]:
    """Every case status in the matrix (passed, failed, engine-failure, crashed (...), ...)."""
    return {r["status"] for c in matrix["cases"] for r in c["runs"].values()}


def broken(matrix: Mapping[str, Any]) -> bool:
    """Whether a case did not run to its end somewhere (crash, time-out, engine failure, error)."""
    return any(
        s.startswith(("crashed", "timed out")) or s in ("engine-failure", "error", "not run")
        for s in run_statuses(matrix)
    )
