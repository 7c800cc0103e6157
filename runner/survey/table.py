"""The survey's cells (how each model ran on each engine), its totals and its Markdown table."""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from reports.markdown_text import text as md_text
from runner.errors import ExitCode
from runner.exec.cases import CaseResult

#: what a cell can be; only RAN counts towards the target, REFUSED is a stated refusal made before running
RAN, REFUSED, CRASHED, ENERGY, FAILED = "ran", "refused", "crashed", "energy", "failed"
KINDS = (RAN, REFUSED, CRASHED, ENERGY, FAILED)
_SHOWN = 110  # characters of a message a cell shows


@dataclass(frozen=True)
class Cell:
    kind: str  # one of KINDS
    text: str  # what the table shows after the kind: the refusal, the exit code, the failure


def cell_of(res: CaseResult) -> Cell:
    """One run's cell: ran (to its end), refused up front (exit 2, the message names what is missing),
    crashed (a bug, exit 70, or the engine's process died), energy (the watchdog), failed (any other engine
    failure, with its time)."""
    r = res.result
    if r is not None:
        if r.status in ("passed", "failed"):
            return Cell(RAN, "")
        failure = r.failure or r.status
        if failure.startswith("energy gain"):
            return Cell(ENERGY, failure)
        return Cell(FAILED, f"t = {r.end_time:.4g} s: {failure}")
    exit = res.exit
    if exit.code is ExitCode.BAD_INPUT:
        return Cell(REFUSED, exit.message)
    if exit.code is ExitCode.INTERNAL_ERROR:
        return Cell(CRASHED, f"exit 70: {exit.message}")
    if res.status in ("crashed", "exited"):
        return Cell(CRASHED, f"{exit.label}: {exit.message}")
    return Cell(FAILED, f"{exit.label}: {exit.message}")


@dataclass
class Survey:
    backends: list[str]
    duration: float
    rows: dict[str, dict[str, Cell]] = field(default_factory=dict)  # model label -> backend -> cell

    def totals(self, backend: str) -> dict[str, int]:
        counts = dict.fromkeys(KINDS, 0)
        for cells in self.rows.values():
            if backend in cells:
                counts[cells[backend].kind] += 1
        return counts

    def ran_fraction(self, backend: str) -> float:
        counts = self.totals(backend)
        return counts[RAN] / max(1, sum(counts.values()))


def _escape(text: str) -> str:
    short = re.sub(r"(?<![\w.~-])(?:/[^\s/:`']+)+/([^\s/:`']+)", r"\1", text)  # absolute paths as file names
    one_line = " ".join(short.split())
    return md_text(one_line if len(one_line) <= _SHOWN else one_line[: _SHOWN - 1] + "…")  # an engine's text, as text


def _cell_text(cell: Cell) -> str:
    return cell.kind if not cell.text else f"{cell.kind}: {_escape(cell.text)}"


def totals_markdown(survey: Survey) -> str:
    lines = [
        "| engine | models | ran | refused | crashed | energy | failed | ran % |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for backend in survey.backends:
        c = survey.totals(backend)
        lines.append(f"| {backend} | {sum(c.values())} | {c[RAN]} | {c[REFUSED]} | {c[CRASHED]} | {c[ENERGY]} | "
                     f"{c[FAILED]} | {100 * survey.ran_fraction(backend):.0f} % |")  # fmt: skip
    return "\n".join(lines) + "\n"


def markdown(survey: Survey) -> str:
    """The table (one row per model, one column per engine) under its totals."""
    head = "| model | " + " | ".join(survey.backends) + " |"
    rule = "|---|" + "---|" * len(survey.backends)
    rows = [
        f"| `{label}` | " + " | ".join(_cell_text(cells[b]) for b in survey.backends) + " |"
        for label, cells in survey.rows.items()
    ]
    return (
        f"# Robot model survey\n\nEach model unmodified on a ground plane, {survey.duration:g} s under gravity "
        '(`scenario robots survey`; the rules in docs/robots.md, "The survey").\n\n'
        + totals_markdown(survey)
        + "\n"
        + "\n".join([head, rule, *rows])
        + "\n"
    )
