"""Rendering results: the verdict table `run`, `check`, `view`, JUnit reports and the pytest plugin print, and
the words of a known limit (the same line on every path)."""

from __future__ import annotations

import io
import math
from typing import TYPE_CHECKING

from rich.markup import escape

from runner.sim.session import RunResult
from runner.sim.verdicts import FAILED, KNOWN_LIMIT, PASSED

if TYPE_CHECKING:
    from rich.table import Table

__all__ = ["known_limit_lines", "render", "verdict_table", "verdict_text"]

#: a known limit (an expected failure, with its measured figure and cause in the message) stands apart
_MARKS = {PASSED: "[green]pass[/]", FAILED: "[bold red]FAIL[/]", KNOWN_LIMIT: "[yellow]known limit[/]"}


def verdict_table(result: RunResult, failures_only: bool = False) -> Table:
    """The verdict table of one run."""
    from rich.table import Table  # here: a quiet run that passes draws no table

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


def render(renderable: object, width: int = 120) -> str:
    """Plain text of a rich renderable (no colour, no markup), for pytest reports and JUnit files."""
    from rich.console import Console

    buf = io.StringIO()
    console = Console(file=buf, width=width, color_system=None, force_terminal=False, highlight=False, emoji=False)
    console.print(renderable)
    return buf.getvalue()


def verdict_text(result: RunResult, failures_only: bool = False) -> str:
    """The verdict table as plain ASCII text (CI pages and JUnit viewers do not all draw box characters)."""
    from rich import box

    if not result.verdicts:
        return ""
    table = verdict_table(result, failures_only)
    table.box = box.ASCII2
    return render(table)


def known_limit_lines(result: RunResult | None) -> list[str]:
    """``known limit: <assertion> on <engine>: measured ...`` for each expected failure of a passed run."""
    if result is None or not result.passed:
        return []
    return [f"known limit: {v.name} {v.message.removeprefix('known limit ')}" for v in result.verdicts
            if v.status == KNOWN_LIMIT]  # fmt: skip
