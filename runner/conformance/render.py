"""The conformance matrix as Markdown (docs/conformance.md is this, committed) and as console tables."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from runner.conformance.matrix import REFUSED

PASS, FAIL, LIMIT, REFUSE = "✅", "❌", "⚠️", "⛔"
RAN = ("passed", "failed", "known limit")  # case statuses of a case that ran to its end


def number(x: Any, signed: bool = False) -> str:
    if x is None:
        return ""
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e6:
        x = int(x)
    if isinstance(x, int):
        return f"{x:+d}" if signed and x else str(x)
    if x == 0:
        return "0"
    return f"{x:+.2e}" if signed else f"{x:.4g}"


def _tolerance(tol: Mapping[str, str]) -> str:
    if not tol:
        return ""
    default = tol.get("default")
    others = [f"{k}: {v}" for k, v in tol.items() if k != "default"]
    return "; ".join(([default] if default is not None else []) + others)


def deviation(cell: Mapping[str, Any]) -> str:
    """|measured - expected| against the tolerance: ``2.48e-06 ≤ 1e-09`` (or ``>``)."""
    error, tol = cell.get("error"), cell.get("tol")
    if error is None:
        return ""
    text = f"{abs(error):.3g}"
    if tol is not None:
        text += f" {'≤' if abs(error) <= tol else '>'} {tol:.3g}"
    return text


def _limit(cell: Mapping[str, Any]) -> str:
    limit = cell["known_limit"]
    error = cell.get("error")
    measured = f"{abs(error):.3g}" if error is not None else cell.get("measured_text", "")
    return f"{LIMIT} known limit: measured {measured} ({limit['cause']}; [doc]({_doc_link(limit['doc'])}))"


def _doc_link(doc: str) -> str:
    """docs/conformance.md links to docs/... relatively."""
    return doc.removeprefix("docs/") if doc.startswith("docs/") else f"../{doc}"


def _cell(cell: Mapping[str, Any], run: Mapping[str, Any], reference: str | None) -> str:
    status = cell["status"]
    if status == "not run":
        return "— refused" if run["status"] == REFUSED else f"— {run['status']}"
    if status == "known limit":
        text = _limit(cell)
    else:
        mark = PASS if status == "pass" else FAIL
        error = cell.get("error")
        text = f"{mark} {deviation(cell)}" if error is not None else mark
        if error is None and cell.get("measured") is not None:
            text += f" {number(cell['measured'])}"
    if status == "fail" and error is None and cell.get("message"):
        text += f" ({cell['message']})"
    if cell.get("vs_reference") is not None and reference:
        text += f"<br>Δ{reference} {number(cell['vs_reference'], signed=True)}"
    return text


def _summary(run_statuses: list[Mapping[str, Any]], checks: list[Mapping[str, Any]], backend: str) -> str:
    status = run_statuses[0]["status"] if run_statuses else "not run"
    passed = sum(c["cells"][backend]["status"] == "pass" for c in checks)
    if status == "passed":
        return f"{PASS} {passed}/{len(checks)}"
    if status == "known limit":
        limits = sum(c["cells"][backend]["status"] == "known limit" for c in checks)
        return f"{LIMIT} {passed}/{len(checks)}, {limits} known limit{'s' * (limits > 1)}"
    if status == "failed":
        return f"{FAIL} {passed}/{len(checks)}"
    if status == REFUSED:
        return f"{REFUSE} refused"
    return f"{FAIL} {status}"


def _escape(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


INTRO = """\
The runner promises ODE semantics (docs/semantics.md). This matrix measures the promise: each scenario in
`scenarios/conformance/` isolates one semantic and states its expected result as an analytic formula in
its assertions, with the derivation in a comment and a tolerance per case (and per backend where a backend
differs by design, for a reason measured and given in the last section). Every case runs on every backend,
each backend in its own process.

In the tables, a cell shows pass (✅) or fail (❌) and the deviation from the analytic value against the
tolerance, |measured − expected| ≤ tol (for checks of the form `max: |x − formula|` the expected value is 0,
so the deviation is the largest over the run). Below it, Δode is the signed difference from the `ode`
backend's measured value (real ODE, the reference). A **known limit** (⚠️) is an engine that cannot meet a
check: the case file says so (`known_limits:` with the measured deviation, its cause and the doc that
explains it), the check runs at the default tolerance and fails there, and the cell shows the measured
deviation and its cause instead of a tick; it is counted apart. It is an expected failure on every path
(`scenario run`, `pytest scenarios/`, JUnit, reports: docs/language.md). A case a backend **refuses** up
front (⛔: exit 2 on `scenario run`, the message naming the measured limit and the engines that can run it,
docs/backends/*.md) is not run there; it is counted apart and shown with its message. The suite fails
when a known limit passes (no longer needed) or measures worse than its documented figure, and when a
per-backend tolerance override is stale (the default tolerance would pass the measured error) or more than
3 times the measured error. Regenerate with `scenario conformance --markdown docs/conformance.md` (exit 0
only when every case passes everywhere, up to its known limits and refusals, and no tolerance is stale or
too wide).
"""


def markdown(matrix: Mapping[str, Any]) -> str:  # noqa: C901 - one document, section by section
    backends = [b["name"] for b in matrix["backends"]]
    reference = matrix.get("reference")
    lines = ["# Conformance matrix", "", INTRO]
    n_checks = sum(len(c["checks"]) for c in matrix["cases"])
    refused = sum(b.get("refused", 0) for b in matrix["backends"])
    upto = "its known limits" + (" and the cases refused up front" if refused else "")
    result = f"**every case passes on every backend, up to {upto}**" if matrix["passed"] else (
        "**some cases fail** (see below)"
    )
    lines += [
        f"Generated on {matrix['date']} by physics-scenarios {matrix['tool_version']} from `{matrix['suite']}`: "
        f"{len(matrix['cases'])} cases, {n_checks} checks. Result: {result}; {totals(matrix)}.",
        "",
        "| backend | engine version | cases passed | cases with known limits | cases refused | run time (s) |",
        "|---|---|---|---|---|---|",
    ]
    for b in matrix["backends"]:
        ref = " (reference)" if b["name"] == reference else ""
        lines.append(
            f"| `{b['name']}`{ref} | {b['engine_version']} | {b['passed']}/{b['cases']} | "
            f"{b.get('known_limits', 0)} | {b.get('refused', 0)} | {b['wall_seconds']} |"
        )
    if matrix.get("audit"):
        lines += ["", "## Tolerance problems", "", "| case | check | backend | problem |", "|---|---|---|---|"]
        lines += [
            f"| `{p['case']}` | {p['check']} | {p['backend']} | {_escape(p['problem'])} |" for p in matrix["audit"]
        ]
    lines += ["", "## Summary", "", "| case | what | " + " | ".join(backends) + " |"]
    lines.append("|---|---|" + "---|" * len(backends))
    for c in matrix["cases"]:
        cells = [_summary([c["runs"][b]], c["checks"], b) for b in backends]
        what = c["description"] or c["semantic"]
        lines.append(f"| `{c['id']}` | {_escape(what)} | " + " | ".join(cells) + " |")
    lines += ["", "## Checks", ""]
    for c in matrix["cases"]:
        lines += [
            f"### `{c['id']}`",
            "",
            _escape(c["semantic"]) + (f" {_escape(c['description'])}" if c["description"] else ""),
        ]
        problems = [
            f"{b}: {c['runs'][b]['status']}"
            for b in backends
            if c["runs"][b]["status"] not in (*RAN, REFUSED)
        ]
        if problems:
            lines += ["", "Not run to the end: " + "; ".join(problems) + "."]
        refusals = [f"{b}: {_escape(c['runs'][b]['message'])}" for b in backends if c["runs"][b]["status"] == REFUSED]
        if refusals:
            lines += ["", "Refused up front by " + "; ".join(refusals)]
        lines += ["", "| check | expected | tolerance | " + " | ".join(backends) + " |"]
        lines.append("|---|---|---|" + "---|" * len(backends))
        for check in c["checks"]:
            cells = [_cell(check["cells"][b], c["runs"][b], reference if b != reference else None) for b in backends]
            lines.append(
                f"| {check['name']}<br>`{_escape(check['measure'])}` | `{_escape(check['expected'])}` | "
                f"{_escape(_tolerance(check['tolerance']))} | " + " | ".join(cells) + " |"
            )
        lines.append("")
    lines += ["## Known limits", ""]
    lines += [
        "Where an engine cannot meet a check, the case file says so; the check runs at the default tolerance",
        "and the matrix shows the measured deviation (largest over the cases sharing the check).",
        "",
        "| scenario | check | backend | measured (case file) | cause | doc |",
        "|---|---|---|---|---|---|",
    ]
    seen: set[tuple[str, str, str]] = set()
    for c in matrix["cases"]:
        for check in c["checks"]:
            for b, limit in check.get("known_limits", {}).items():
                if (c["file"], check["name"], b) not in seen:
                    seen.add((c["file"], check["name"], b))
                    lines.append(
                        f"| `{c['file']}` | {check['name']} | {b} | {limit['measured']:.3g} | "
                        f"{_escape(limit['cause'])} | [{limit['doc']}]({_doc_link(limit['doc'])}) |"
                    )
    lines += ["", "## Per-backend tolerances", ""]
    lines += [
        "Where a backend differs from ODE by design, a case states a tolerance for it; each one comes with the",
        "measured reason, given in the assertion's `description` and repeated here. No other tolerance differs",
        "between backends.",
        "",
        "| scenario | checks | tolerances | reason |",
        "|---|---|---|---|",
    ]
    groups: dict[tuple[str, str, str], list[str]] = {}
    for c in matrix["cases"]:
        for check in c["checks"]:
            if any(k != "default" for k in check["tolerance"]):
                key = (c["file"], _tolerance(check["tolerance"]), check["description"])
                names = groups.setdefault(key, [])
                if check["name"] not in names:
                    names.append(check["name"])
    for (file, tol, reason), names in groups.items():
        lines.append(f"| `{file}` | {', '.join(names)} | {_escape(tol)} | {_escape(reason)} |")
    return "\n".join(lines).rstrip() + "\n"


def console(matrix: Mapping[str, Any], out: Console, quiet: bool = False) -> None:
    """The summary table (unless quiet), then the checks that failed, then the result line."""
    backends = [b["name"] for b in matrix["backends"]]
    table = Table(title="conformance", title_justify="left")
    table.add_column("case")
    for b in matrix["backends"]:
        table.add_column(f"{b['name']} {b['engine_version']}")
    for c in matrix["cases"]:
        row = []
        for b in backends:
            text = _summary([c["runs"][b]], c["checks"], b)
            colour = "green" if text.startswith(PASS) else "yellow" if text.startswith((LIMIT, REFUSE)) else "red"
            row.append(f"[{colour}]{text}[/]")
        table.add_row(c["id"], *row)
    if not quiet:
        out.print(table)
    bad = Table(title="checks that failed", title_justify="left")
    for col in ("case", "check", "backend", "measured", "expected", "error", "vs ode"):
        bad.add_column(col, overflow="fold")
    rows = 0
    for c in matrix["cases"]:
        for check in c["checks"]:
            for b in backends:
                cell = check["cells"][b]
                if cell["status"] != "fail":  # a case that did not run is listed below, once
                    continue
                bad.add_row(
                    c["id"],
                    check["name"],
                    b,
                    cell.get("measured_text", ""),
                    cell.get("expected_text", ""),
                    number(cell.get("error"), signed=True),
                    number(cell.get("vs_reference"), signed=True),
                )
                rows += 1
    if rows:
        out.print(bad)
    for c in matrix["cases"]:
        for b in backends:
            run = c["runs"][b]
            if run["status"] == REFUSED:
                out.print(f"[yellow]{c['id']} refused by {b}[/]: {run['message']}")
            elif run["status"] not in RAN:
                first = run["message"].strip().splitlines()[-1:] if run["message"] else []
                last = f": {escape(first[0])}" if first else ""
                out.print(f"[red]{escape(c['id'])} on {b}: {run['status']}[/]{last}")
    for p in matrix.get("audit", []):
        out.print(f"[red]{escape(p['case'])} {escape(p['check'])} on {p['backend']}: {escape(p['problem'])}[/]")
    colour = "green" if matrix["passed"] else "red"
    out.print(f"[bold {colour}]{totals(matrix)}[/] on {', '.join(backends)}")


def totals(matrix: Mapping[str, Any]) -> str:
    """``87 pass, 2 known limits of 89 case runs`` (cases x backends; ``, 4 refused`` before ``of`` if any)."""
    passed = sum(b["passed"] for b in matrix["backends"])
    limits = sum(b.get("known_limits", 0) for b in matrix["backends"])
    total = sum(b["cases"] for b in matrix["backends"])
    refused = sum(b.get("refused", 0) for b in matrix["backends"])
    text = f"{passed} pass, {limits} known limit{'' if limits == 1 else 's'}"
    text += f", {refused} refused of {total} case runs" if refused else f" of {total} case runs"
    problems = len(matrix.get("audit", []))
    return text + (f", {problems} tolerance problem{'' if problems == 1 else 's'}" if problems else "")
