"""Rendering results for the terminal: what `run`, `check`, JUnit reports and the pytest plugin print."""

from __future__ import annotations

import math

from rich.markup import escape
from rich.table import Table

from runner.sim.session import RunResult


def verdict_table(result: RunResult, failures_only: bool = False) -> Table:
    """The verdict table of one run (also used by `check`, JUnit reports and the pytest plugin)."""
    title = f"{result.scenario} · {result.variant} · {result.backend}"
    table = Table(title=title, title_justify="left", show_lines=False)
    for col in ("assertion", "result", "measured", "expected", "time"):
        table.add_column(col, overflow="fold")
    for v in result.verdicts:
        if failures_only and v.passed:
            continue
        mark = "[green]pass[/]" if v.passed else "[bold red]FAIL[/]"
        when = "" if v.time is None or math.isinf(v.time) else f"{v.time:.3f}"
        measured = v.measured + (f" ({v.message})" if v.message and not v.passed else "")
        table.add_row(escape(v.name), mark, escape(measured), escape(v.expected), when)
    return table
