"""The conformance matrix: every check of every case on every backend, against the analytic value and
against the reference backend (``ode``), as plain JSON-ready data.

A cell holds the raw measured value, the analytic target and the tolerance the case states for that
backend, the error ``measured - target`` and the difference ``measured - reference's measured``; its
status is the runner's verdict (pass / fail), ``known limit`` (an engine that cannot meet the check, failing
at the default tolerance as its case file says), or ``not run`` when the case did not complete on the backend
(crash, time-out, engine failure, unsupported feature). A case whose only failures are known limits has the
status ``known limit``. A case a backend refuses up front (``unsupported``: UnsupportedFeature, the
message naming the measured limit and the engines that can run it, docs/backends/*.md) is an answer, not a
breakage: it is counted apart as refused. :mod:`runner.conformance.audit` checks the tolerances themselves
(stale or too wide overrides, known limits no longer needed); its problems are in ``audit``. The matrix
passes only when every case passed (or failed at its known limits only, or was refused where
the suite's ``expected-refusals.json`` names the refusal) on every backend and the audit found nothing.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from backends.registry import REFERENCE_BACKEND
from runner.conformance import audit
from runner.conformance.cases import Case, Check
from runner.conformance.pool import BackendRun
from runner.version import tool_version

REFERENCE = REFERENCE_BACKEND
#: A case's status when its backend refused it before the run (runner.conformance.worker).
REFUSED = "unsupported"
#: Case statuses that leave the matrix passing (a refusal only where the suite expects it).
ACCEPTED = ("passed", audit.KNOWN_LIMIT)
#: Beside a suite's case files: {case file: [backends that refuse it up front by a measured, documented
#: limit]}. Any other refusal (a mapping that stopped accepting a case) fails the matrix like a crash.
EXPECTED_REFUSALS_FILE = "expected-refusals.json"


def expected_refusals(folder: Path) -> dict[str, frozenset[str]]:
    """The suite folder's expected refusals (none without the file)."""
    try:
        found = json.loads((folder / EXPECTED_REFUSALS_FILE).read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {}
    return {str(k): frozenset(map(str, v)) for k, v in found.items() if not str(k).startswith("_")}


def _accepted(status: str, backend: str, expected: frozenset[str]) -> bool:
    return status in ACCEPTED or (status == REFUSED and backend in expected)


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
        "default_tol": check.get("default_tol"),
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
    problems: list[dict[str, str]] = []
    folders = {case.path.parent: expected_refusals(case.path.parent) for case in cases}
    expected = {case.id: folders[case.path.parent].get(case.file, frozenset()) for case in cases}
    for case in cases:
        results = {b: runs[b].results.get(case.id) for b in backends}
        per_backend = {b: _checks_by_index(results[b], len(case.checks)) for b in backends}
        checks: list[dict[str, Any]] = []
        for i, check in enumerate(case.checks):
            ref = per_backend[reference][i] if reference else None
            cells = {b: _cell(per_backend[b][i], ref if b != reference else None) for b in backends}
            problems += _audit(case.id, check, cells)
            checks.append(
                {
                    "name": check.name,
                    "kind": check.kind,
                    "measure": check.measure,
                    "expected": check.expected,
                    "tolerance": check.tolerance,
                    "description": check.description,
                    "known_limits": check.known_limits,
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
                        "status": _status((results[b] or {}).get("status", "not run"), [c["cells"][b] for c in checks]),
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
                "known_limits": sum(c["runs"][b]["status"] == audit.KNOWN_LIMIT for c in out_cases),
                "refused": sum(c["runs"][b]["status"] == REFUSED for c in out_cases),
                "cases": len(out_cases),
            }
            for b in backends
        ],
        "cases": out_cases,
        "audit": problems,
        "passed": bool(out_cases)
        and not problems
        and all(_accepted(r["status"], b, expected[c["id"]]) for c in out_cases for b, r in c["runs"].items()),
    }


def _audit(case: str, check: Check, cells: Mapping[str, dict[str, Any]]) -> list[dict[str, str]]:
    """The tolerance problems of one check's cells (marking its known limits' cells on the way)."""
    out = []
    for b, cell in cells.items():
        if b in check.known_limits:
            problem = audit.known_limit(cell, check.known_limits[b])
        else:
            problem = audit.override(cell) if b in check.tolerance else None
        if problem:
            out.append({"case": case, "check": check.name, "backend": b, "problem": problem})
    return out


def _status(status: str, cells: Sequence[Mapping[str, Any]]) -> str:
    """The case's status from the runner's, which already judged known limits (an expected failure passes
    the run, an unexpected pass fails it): a passed case with a known limit's cell is a ``known limit``."""
    if status == "passed" and any(c["status"] == audit.KNOWN_LIMIT for c in cells):
        return audit.KNOWN_LIMIT
    return status


def run_statuses(matrix: Mapping[str, Any]) -> set[str]:
    """Every case status in the matrix (passed, failed, engine-failure, crashed (...), ...)."""
    return {r["status"] for c in matrix["cases"] for r in c["runs"].values()}


def broken(matrix: Mapping[str, Any]) -> bool:
    """Whether a case did not run to its end somewhere (crash, time-out, engine failure, error)."""
    return any(
        s.startswith(("crashed", "timed out")) or s in ("engine-failure", "error", "not run")
        for s in run_statuses(matrix)
    )
