"""The conformance matrix as Markdown (docs/conformance.md is this, committed) and as console tables."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.console import Console
from rich.table import Table

PASS, FAIL = "✅", "❌"


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


def _cell(cell: Mapping[str, Any], run: Mapping[str, Any], reference: str | None) -> str:
    status = cell["status"]
    if status == "not run":
        return f"— {run['status']}"
    mark = PASS if status == "pass" else FAIL
    error = cell.get("error")
    text = f"{mark} {number(error, signed=True)}" if error is not None else mark
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
    if status == "failed":
        return f"{FAIL} {passed}/{len(checks)}"
    return f"{FAIL} {status}"


def _escape(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


INTRO = """\
The runner promises ODE semantics (docs/semantics.md). This matrix measures the promise: each scenario in
`scenarios/conformance/` isolates one semantic and states its expected result as an analytic formula in
its assertions, with the derivation in a comment and a tolerance per case (and per backend where a backend
differs by design, for a reason measured and given in the last section). Every case runs on every backend,
each backend in its own process.

In the tables, a cell shows pass (✅) or fail (❌) and the error against the analytic value
(measured − expected; for checks of the form `max: |x − formula|` the expected value is 0, so the error is
the largest deviation over the run). Below it, Δode is the difference from the `ode` backend's measured value
(real ODE, the reference). Regenerate with
`scenario conformance --markdown docs/conformance.md` (exit 0 only when every case passes everywhere).
"""


def markdown(matrix: Mapping[str, Any]) -> str:  # noqa: C901 - one document, section by section
    backends = [b["name"] for b in matrix["backends"]]
    reference = matrix.get("reference")
    lines = ["# Conformance matrix", "", INTRO]
    n_checks = sum(len(c["checks"]) for c in matrix["cases"])
    lines += [
        f"Generated on {matrix['date']} by physics-scenarios {matrix['tool_version']} from `{matrix['suite']}`: "
        f"{len(matrix['cases'])} cases, {n_checks} checks. Result: "
        + ("**every case passes on every backend**." if matrix["passed"] else "**some cases fail** (see below)."),
        "",
        "| backend | engine version | cases passed | run time (s) |",
        "|---|---|---|---|",
    ]
    for b in matrix["backends"]:
        ref = " (reference)" if b["name"] == reference else ""
        lines.append(
            f"| `{b['name']}`{ref} | {b['engine_version']} | {b['passed']}/{b['cases']} | {b['wall_seconds']} |"
        )
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
            f"{b}: {c['runs'][b]['status']}" for b in backends if c["runs"][b]["status"] not in ("passed", "failed")
        ]
        if problems:
            lines += ["", "Not run to the end: " + "; ".join(problems) + "."]
        lines += ["", "| check | expected | tolerance | " + " | ".join(backends) + " |"]
        lines.append("|---|---|---|" + "---|" * len(backends))
        for check in c["checks"]:
            cells = [_cell(check["cells"][b], c["runs"][b], reference if b != reference else None) for b in backends]
            lines.append(
                f"| {check['name']}<br>`{_escape(check['measure'])}` | `{_escape(check['expected'])}` | "
                f"{_escape(_tolerance(check['tolerance']))} | " + " | ".join(cells) + " |"
            )
        lines.append("")
    lines += ["## Per-backend tolerances", ""]
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
            row.append(f"[green]{text}[/]" if text.startswith(PASS) else f"[red]{text}[/]")
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
            if run["status"] not in ("passed", "failed"):
                first = run["message"].strip().splitlines()[-1:] if run["message"] else []
                out.print(f"[red]{c['id']} on {b}: {run['status']}[/]" + (f": {first[0]}" if first else ""))
    passed = sum(b["passed"] for b in matrix["backends"])
    total = sum(b["cases"] for b in matrix["backends"])
    colour = "green" if matrix["passed"] else "red"
    out.print(f"[bold {colour}]{passed}/{total} case runs passed[/] on {', '.join(backends)}")
