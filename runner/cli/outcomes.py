"""How `run`, `sweep` and `compare` print a case that ended (the same words on every execution path).

A case that completed prints its verdicts (:func:`print_result`). A case that did not (bad input found
while running, a missing engine, a crash, a time-out, a full disk, a bug) prints its first message line
(:attr:`runner.exec.cases.CaseResult.headline`, the same line the CLI prints for the same error raised
in its own process) on stderr, then what explains it: every located issue of a scenario error, the
engine's last output of a crash, the child's traceback of a bug when ``SCENARIO_DEBUG=1``.
"""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING

from rich.console import Console
from rich.markup import escape

from runner.ci.render import known_limit_lines, verdict_table
from runner.errors import ExitCode
from runner.exec.cases import CaseResult
from runner.language.load import LoadedScenario
from runner.sim.session import RunResult
from runner.sim.verdicts import KNOWN_LIMIT

if TYPE_CHECKING:  # imported when a JUnit report is asked for (xml.etree costs every run's start-up)
    from runner.ci.junit import JUnitCase

__all__ = ["case_line", "debug", "in_tests", "junit_case", "print_problem", "print_result", "print_summary",
           "summary_line"]


def in_tests() -> bool:
    """Inside the test suite (pytest sets PYTEST_CURRENT_TEST, and commands it starts inherit it), unless
    ``SCENARIO_DEBUG=0`` says to behave as for a user."""
    return "PYTEST_CURRENT_TEST" in os.environ and os.environ.get("SCENARIO_DEBUG") != "0"


def debug() -> bool:
    """Tracebacks for bugs: ``SCENARIO_DEBUG=1``, and in the test suite."""
    return os.environ.get("SCENARIO_DEBUG") == "1" or in_tests()


def print_result(out: Console, result: RunResult, quiet: bool) -> None:
    """A completed run: its engine failure (body, time, last good state), verdicts and trace."""
    if result.failure:
        out.print(
            f"[bold red]engine failure[/] in {escape(result.scenario)} · {escape(result.variant)} · "
            f"{escape(result.backend)}: {escape(result.failure)}"
        )
        detail = result.extra.get("last_good")
        if detail:
            out.print(f"  last good state of `{escape(str(result.extra.get('body')))}`: {escape(json.dumps(detail))}")
    if result.engine_messages:
        out.print(f"  {result.engine_messages} engine message(s) from {result.backend}, in the trace's log (`engine`)")
    limits = any(v.status == KNOWN_LIMIT for v in result.verdicts)
    if result.verdicts and (not quiet or not result.passed or limits):
        out.print(verdict_table(result, failures_only=quiet))
    if result.trace and not quiet:
        out.print(f"  trace: {escape(result.trace)}")


def print_problem(err: Console, res: CaseResult) -> None:
    """A case that did not complete: its first message line, then what explains it (stderr)."""
    exit = res.exit
    issues = getattr(res.error, "issues", None)
    if issues:
        for issue in issues:
            err.print(f"[bold red]{escape(exit.label)}:[/] {escape(str(issue))}", markup=True)
    else:
        err.print(f"[bold red]{escape(exit.label)}:[/] {escape(exit.message)}", markup=True)
    if res.status in ("crashed", "exited") and res.output.strip():
        err.print(escape(res.output.strip()[-2000:]), markup=True, highlight=False)
    if res.trace is not None and res.trace.endswith(".partial"):
        err.print(f"  trace kept: {escape(res.trace)} (read it with `scenario inspect --recover`)")
    remote = getattr(res.error, "remote_traceback", "")
    if remote and debug():
        err.print(escape(remote), markup=True, highlight=False)


def summary_line(res: CaseResult, scenario: str, variant: str) -> str:
    """``  <scenario> · <variant> · <backend>: <first message line>`` for a case that did not pass."""
    return case_line(scenario, variant, res.case.backend, res.headline)


def case_line(scenario: str, variant: str, backend: str, headline: str) -> str:
    """``  <scenario> · <variant> · <backend>: <label>: <message>``, the label in red (`run`, `check`)."""
    where = f"{escape(scenario)} · {escape(variant)} · {escape(backend)}"
    label, _, rest = headline.partition(": ")
    return f"  {where}: [red]{escape(label)}[/]" + (f": {escape(rest)}" if rest else "")


def print_summary(out: Console, results: list[CaseResult], names: list[tuple[str, str]]) -> None:
    passed = sum(r.passed for r in results)
    completed = [r.result for r in results if r.result is not None]
    checks = sum(len(r.verdicts) for r in completed)
    failed_checks = sum(not v.passed for r in completed for v in r.verdicts)
    limits = sum(v.status == KNOWN_LIMIT for r in completed for v in r.verdicts)
    colour = "green" if passed == len(results) else "red"
    shown = f"{checks - failed_checks - limits}/{checks} assertions"
    shown += f", {limits} known limit{'s' * (limits > 1)}" if limits else ""
    out.print(f"[bold {colour}]{passed}/{len(results)} runs passed[/] ({shown})")
    for res, (scenario, variant) in zip(results, names, strict=True):
        if not res.passed:
            out.print(summary_line(res, scenario, variant))
        for text in known_limits(res):
            where = f"{escape(scenario)} · {escape(variant)} · {escape(res.case.backend)}"
            out.print(f"  {where}: [yellow]{escape(text)}[/]", highlight=False)


def known_limits(res: CaseResult) -> list[str]:
    """``known limit: <assertion> on <engine>: measured ...`` for each expected failure of a passed run
    (the same line on every path: `run`, `-j`, `--isolate`, Ray, `compare`, `check`, the pytest plugin)."""
    return known_limit_lines(res.result if res.passed else None)


_KINDS = {
    ExitCode.BAD_INPUT: "bad-input",
    ExitCode.ENGINE_FAILURE: "engine-failure",
    ExitCode.INTERNAL_ERROR: "internal-error",
    ExitCode.OUTPUT_ERROR: "output-error",
}


def junit_case(res: CaseResult, loaded: LoadedScenario | None) -> JUnitCase:
    """A case as JUnit sees it: a failed assertion is a failure, anything that stopped it an error."""
    from runner.ci.junit import JUnitCase, from_result, suite_properties

    if res.result is not None:
        return from_result(res.result, loaded)
    exit = res.exit
    stopped = res.status in ("crashed", "timed-out", "over-memory", "exited")
    kind = "engine-crash" if stopped else _KINDS.get(exit.code, "error")
    scenario = loaded.model.scenario if loaded is not None else res.case.scenario
    variant = loaded.variant if loaded is not None else (res.case.variant or "base")
    text = exit.message + (f"\n{res.output.strip()[-2000:]}" if res.output.strip() else "")
    return JUnitCase(scenario, variant, res.case.backend, "error", kind=kind, message=exit.headline, text=text,
                     properties=suite_properties(res.case.backend, loaded))  # fmt: skip
