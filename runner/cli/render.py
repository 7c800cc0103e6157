"""Rendering results for the terminal: what `run`, `check`, JUnit reports and the pytest plugin print."""

from __future__ import annotations

import math

from rich.markup import escape
from rich.table import Table

from runner.sim.session import RunResult
from runner.sim.verdicts import FAILED, KNOWN_LIMIT, PASSED

#: a known limit (an expected failure, with its measured figure and cause in the message) stands apart
_MARKS = {PASSED: "[green]pass[/]", FAILED: "[bold red]FAIL[/]", KNOWN_LIMIT: "[yellow]known limit[/]"}


def verdict_table(result: RunResult, failures_only: bool = False) -> Table:
    """The verdict table of one run (also used by `check`, JUnit reports and the pytest plugin)."""
    title = f"{result.scenario} · {result.variant} · {result.backend}"
    table = Table(title=title, title_justify="left", show_lines=False)
    for col in ("assertion", "result", "measured", "expected", "time"):
        table.add_column(col, overflow="fold")
    for v in result.verdicts:
        if failures_only and v.status == PASSED:
            continue
        mark = _MARKS[v.status]
        when = "" if v.time is None or math.isinf(v.time) else f"{v.time:.3f}"
        measured = v.measured + (f" ({v.message})" if v.message and v.status != PASSED else "")
        table.add_row(escape(v.name), mark, escape(measured), escape(v.expected), when)
    return table
