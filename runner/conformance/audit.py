"""Honest tolerances (issue 17): what the matrix checks about the suite's own tolerances, cell by cell.

A per-backend tolerance override must be needed and no wider than the error it covers:

* **stale**: the backend's measured error |measured - expected| is within the default tolerance, so the
  default would pass it;
* **too wide**: the override is more than ``WIDTH_FACTOR`` times the measured error (a tolerance that
  would let the engine drift that far without anyone noticing).

A **known limit** (an assertion's ``known_limits: {backend: {measured, cause, doc}}``) is an engine that
cannot meet the check: it runs at the default tolerance and must fail there. The cell shows the measured
deviation with its cause instead of a tick. It is a problem when:

* the check passes: the known limit is no longer needed (remove the entry);
* the measured error exceeds the documented figure by more than ``DOC_SLACK``: the engine got worse, or
  the figure in the case file and the doc it links is stale.

Every problem fails the matrix, so `scenario conformance` (CI) exits 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

#: An override may be at most this many times the error it covers (issue 17).
WIDTH_FACTOR = 3.0
#: A known limit's live error may exceed its documented figure by this fraction: the figure is written
#: with two significant digits, rounded up, so rounding alone never trips it.
DOC_SLACK = 0.05

KNOWN_LIMIT = "known limit"


def _abs_error(cell: Mapping[str, Any]) -> float | None:
    error = cell.get("error")
    return abs(float(error)) if error is not None else None


def known_limit(cell: dict[str, Any], limit: Mapping[str, Any]) -> str | None:
    """Mark a cell of a known limit (status ``known limit``); the problem, if there is one."""
    if cell["status"] == "not run":
        return None
    cell["known_limit"] = dict(limit)
    if cell["status"] == "pass":
        cell["status"] = "fail"
        return (
            f"known limit no longer needed: passes at the default tolerance (error {_g(_abs_error(cell))}, "
            f"tolerance {_g(cell.get('tol'))}); remove its `known_limits` entry"
        )
    cell["status"] = KNOWN_LIMIT
    error = _abs_error(cell)
    stated = float(limit["measured"])
    if error is not None and error > stated * (1 + DOC_SLACK):
        return (
            f"known limit worse than documented: measured {_g(error)}, the case file and {limit['doc']} say "
            f"{_g(stated)}"
        )
    return None


def override(cell: Mapping[str, Any]) -> str | None:
    """The problem with a backend's tolerance override, if any (the cell ran with the override)."""
    error, tol, default = _abs_error(cell), cell.get("tol"), cell.get("default_tol")
    if cell["status"] == "not run" or error is None or tol is None:
        return None
    if default is not None and error <= default:
        return (
            f"stale override: measured error {_g(error)} is within the default tolerance {_g(default)}; "
            "remove the override"
        )
    if tol > WIDTH_FACTOR * error:
        return (
            f"override too wide: tolerance {_g(tol)} is more than {WIDTH_FACTOR:g} x the measured error "
            f"{_g(error)}; derive a tighter one or make it a known limit"
        )
    return None


def _g(x: Any) -> str:
    return "?" if x is None else f"{float(x):.3g}"
