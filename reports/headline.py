"""The words at the top of a report and of each case: assertions and agreement, said apart.

*Assertions* pass when every run finished and every assertion passed. *Agreement* holds when no
quantity (reports.quantities) of any run strays further from its truth than its threshold. The badge
reads PASS only when both hold; otherwise it says which does not, e.g. "assertions pass · 3 quantities
diverge" or "2 assertions fail · 1 run crashed · quantities agree". The exit code is not the badge: it
follows the assertions, and agreement only when ``--max-divergence`` asks for it (docs/report-schema.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["headline", "merge"]


def _plural(n: int, one: str, many: str | None = None) -> str:
    return f"{n} {one if n == 1 else (many or one + 's')}"


def headline(runs: Sequence[dict[str, Any]], quantities: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The headline of one case from its runs and quantities (as in the comparison document)."""
    failed = sum(r["assertions"]["failed"] for r in runs)
    total = sum(r["assertions"]["total"] for r in runs)
    broken = [r for r in runs if r["status"] not in ("passed", "failed")]
    diverging = [q for q in quantities if q["diverging"]]
    firsts = [q["first_over"] for q in diverging if q["first_over"] is not None]
    return _words({
        "assertions": {"passed": failed == 0 and not broken, "failed": failed, "total": total,
                       "runs_not_finished": len(broken), "not_finished": [r["label"] for r in broken]},
        "agreement": {"agrees": not diverging, "quantities": len(quantities), "diverging": len(diverging),
                      "first_over": min(firsts) if firsts else None,
                      "backends": sorted({b for q in diverging for b in q["diverging"]})},
    })  # fmt: skip


def merge(parts: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The overall headline from the cases' headlines."""
    a = [p["assertions"] for p in parts]
    g = [p["agreement"] for p in parts]
    firsts = [x["first_over"] for x in g if x["first_over"] is not None]
    return _words({
        "cases": len(parts),
        "assertions": {"passed": all(x["passed"] for x in a), "failed": sum(x["failed"] for x in a),
                       "total": sum(x["total"] for x in a), "runs_not_finished": sum(x["runs_not_finished"] for x in a),
                       "not_finished": [label for x in a for label in x["not_finished"]]},
        "agreement": {"agrees": all(x["agrees"] for x in g), "quantities": sum(x["quantities"] for x in g),
                      "diverging": sum(x["diverging"] for x in g), "first_over": min(firsts) if firsts else None,
                      "cases_diverging": sum(not x["agrees"] for x in g),
                      "backends": sorted({b for x in g for b in x["backends"]})},
    })  # fmt: skip


def _words(h: dict[str, Any]) -> dict[str, Any]:
    a, g = h["assertions"], h["agreement"]
    said = []
    if a["failed"]:
        said.append(f"{_plural(a['failed'], 'assertion')} fail" + ("s" if a["failed"] == 1 else ""))
    if a["runs_not_finished"]:
        kinds = sorted(set(a["not_finished"]))
        said.append(f"{_plural(a['runs_not_finished'], 'run')} {' / '.join(kinds)}")
    if not said:
        said.append("assertions pass")
    if g["diverging"]:
        when = f" from {g['first_over']:g} s" if g["first_over"] is not None else ""
        if h.get("cases", 1) > 1:
            when = f" in {g['cases_diverging']} of {h['cases']} cases" + when
        said.append(f"{_plural(g['diverging'], 'quantity', 'quantities')} diverge{'s' if g['diverging'] == 1 else ''}"
                    f"{when}")  # fmt: skip
    elif g["quantities"]:
        said.append("quantities agree")
    else:
        said.append("no quantity compared")
    ok = a["passed"] and g["agrees"]
    return {**h, "badge": "PASS" if ok else "FAIL", "text": " · ".join(said)}
