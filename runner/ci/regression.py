"""Recording cases into golden files and checking cases against them, running them through ``runner.exec``.

What `scenario baseline`, `scenario check` and the pytest plugin share. Each case runs as every command runs
it (:class:`runner.exec.executors.LocalExecutor` or any executor: a worker process, its result or error with
its class), so its verdict is the one `scenario run` gives: a case that does not complete (bad input, a
capability its engine lacks, a missing engine, a crash, a full disk) ends with `run`'s exit code and first
line, and is never compared. A case that completes is recorded from, or compared with, the trace its run
wrote (read back with :mod:`reports.trace_reader`), so a golden file holds exactly what the trace holds.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from reports.trace_reader import read_trace
from runner.ci.golden import (
    DEFAULT_TOLERANCES,
    BaselineError,
    Recording,
    Tol,
    Tolerances,
    golden_name,
    record_from_trace,
    sample_every,
    write_golden,
)
from runner.ci.golden_compare import Comparison, compare
from runner.ci.golden_plot import write_divergence_plot
from runner.ci.golden_read import read_golden
from runner.ci.render import verdict_text
from runner.errors import ExitCode
from runner.exec.cases import CaseResult, case_of
from runner.exec.executors import Executor, LocalExecutor
from runner.exec.exits import Exit
from runner.language.load import LoadedScenario
from runner.sim.session import RunResult

__all__ = ["CaseOutcome", "check_cases", "comparison_lines", "golden_path", "outcome_text",
           "parse_tolerance_options", "record_cases"]  # fmt: skip

PASSED, FAILURE, ERROR = "passed", "failure", "error"
Pairs = Sequence[tuple[LoadedScenario, str]]  # (case, backend)


@dataclass
class CaseOutcome:
    """One scenario x variant x backend run and checked against its golden file."""

    loaded: LoadedScenario
    run: CaseResult  # how the run ended (runner.exec)
    golden: Path
    comparison: Comparison | None = None
    plot: Path | None = None
    problem: str = ""  # why a completed run could not be compared: no baseline, a bad one, no trace
    problem_kind: str = ""  # missing-baseline | bad-input

    @property
    def backend(self) -> str:
        return self.run.case.backend

    @property
    def result(self) -> RunResult | None:
        return self.run.result

    @property
    def label(self) -> str:
        return f"{self.loaded.model.scenario} · {self.loaded.variant} · {self.backend}"

    @property
    def diverges(self) -> bool:
        return self.comparison is not None and not self.comparison.ok

    @property
    def exit(self) -> Exit:
        """The run's exit (runner.exec.exits), unless it completed: then a baseline that cannot be used is bad
        input (2), a failed assertion 1, a divergence 1 ("diverges: ..."), else the run's (0)."""
        run = self.run.exit
        if self.run.result is None or run.code not in (ExitCode.OK, ExitCode.ASSERTION_FAILED):
            return run
        if self.problem:
            return Exit(ExitCode.BAD_INPUT, "error", self.problem)
        if run.code == ExitCode.OK and self.comparison is not None and self.diverges:
            first = comparison_lines(self.comparison)[0]  # "first divergence: t=..."
            return Exit(ExitCode.ASSERTION_FAILED, "diverges", f"{first} (baseline {self.golden.name})")
        return run

    @property
    def outcome(self) -> str:
        """passed | failure (an assertion or a divergence) | error (anything that stopped the check)."""
        code = self.exit.code
        return PASSED if code == ExitCode.OK else FAILURE if code == ExitCode.ASSERTION_FAILED else ERROR

    @property
    def error_kind(self) -> str:
        """For JUnit, as `run`'s report names it: missing-baseline | bad-input | engine-failure | engine-crash |
        output-error | internal-error."""
        if self.problem_kind and self.exit.code == ExitCode.BAD_INPUT and self.exit.message == self.problem:
            return self.problem_kind
        if self.run.status in ("crashed", "timed-out", "over-memory", "exited"):
            return "engine-crash"
        return {ExitCode.BAD_INPUT: "bad-input", ExitCode.INTERNAL_ERROR: "internal-error",
                ExitCode.OUTPUT_ERROR: "output-error"}.get(self.exit.code, "engine-failure")  # fmt: skip


def golden_path(directory: Path, loaded: LoadedScenario, backend: str) -> Path:
    return directory / golden_name(loaded.model.scenario, loaded.variant, backend)


def run_cases(pairs: Pairs, out_dir: Path, executor: Executor | None = None,
              on_result: Callable[[int, CaseResult], None] | None = None) -> list[CaseResult]:  # fmt: skip
    """Each (case, backend) run as `scenario run` runs it, its trace in ``out_dir``; results in order."""
    cases = [case_of(loaded, backend, out_dir) for loaded, backend in pairs]
    return (executor or LocalExecutor()).run(cases, on_result)


def _recording(res: CaseResult, every: int, tolerances: dict[str, Tol] | None = None) -> Recording | None:
    """The completed run's trace as a recording (None: the run did not complete or left no finished trace)."""
    if res.result is None or res.result.trace is None or not Path(res.result.trace).is_file():
        return None
    return record_from_trace(read_trace(res.result.trace), every, tolerances)


def record_cases(pairs: Pairs, directory: Path, out_dir: Path | None = None, period: float | None = None,
                 executor: Executor | None = None) -> list[tuple[CaseResult, Path, Recording | None]]:  # fmt: skip
    """Run each case and write its golden file (its traces kept in ``out_dir`` if given). An existing file keeps
    its tolerance lines and, unless ``period`` is given, its sampling. A case that did not complete writes
    nothing (its recording is None; its result says why)."""
    with tempfile.TemporaryDirectory(prefix="scenario-baseline-") as tmp:
        results = run_cases(pairs, out_dir if out_dir is not None else Path(tmp), executor)
        done = []
        for (loaded, backend), res in zip(pairs, results, strict=True):
            path = golden_path(directory, loaded, backend)
            previous = read_golden(path) if path.exists() else None
            if period is not None or previous is None:
                every = sample_every(loaded.model.world.dt, period)
            else:
                every = int(previous.header["every"])
            tolerances = previous.tolerances if previous is not None else dict(DEFAULT_TOLERANCES)
            rec = _recording(res, every, tolerances)
            if rec is not None:
                write_golden(path, rec)
            if out_dir is None and res.result is not None:
                res.result.trace = res.trace = None  # it was in the temporary folder
            done.append((res, path, rec))
    return done


def check_cases(pairs: Pairs, directory: Path, out_dir: Path, overrides: dict[str, Tol] | None = None,
                executor: Executor | None = None,
                on_outcome: Callable[[CaseOutcome], None] | None = None) -> list[CaseOutcome]:  # fmt: skip
    """Run each case and compare it with its golden file; ``on_outcome`` sees each outcome, in case order,
    as soon as it and the ones before it are done."""
    outcomes: dict[int, CaseOutcome] = {}
    shown = 0

    def arrived(index: int, res: CaseResult) -> None:
        nonlocal shown
        loaded, backend = pairs[index]
        outcomes[index] = check_case(loaded, res, directory, out_dir, overrides)
        while shown in outcomes:
            if on_outcome is not None:
                on_outcome(outcomes[shown])
            shown += 1

    run_cases(pairs, out_dir, executor, arrived)
    return [outcomes[i] for i in range(len(pairs))]


def check_case(loaded: LoadedScenario, res: CaseResult, directory: Path, out_dir: Path | None,
               overrides: dict[str, Tol] | None = None) -> CaseOutcome:  # fmt: skip
    """Compare a case's run with its golden file (a run that did not complete is not compared)."""
    path = golden_path(directory, loaded, res.case.backend)
    outcome = CaseOutcome(loaded, res, path)
    if outcome.exit.code not in (ExitCode.OK, ExitCode.ASSERTION_FAILED):
        return outcome
    if not path.exists():
        hint = f"record it with `scenario baseline {loaded.path} --backend {res.case.backend} --baseline {directory}`"
        outcome.problem, outcome.problem_kind = f"no baseline {path}; {hint}", "missing-baseline"
        return outcome
    try:
        expected = read_golden(path)
    except BaselineError as exc:
        outcome.problem, outcome.problem_kind = str(exc), "bad-input"
        return outcome
    got = _recording(res, int(expected.header["every"]))
    if got is None:
        outcome.problem, outcome.problem_kind = f"the run left no finished trace to compare with {path}", "bad-input"
        return outcome
    tolerances = Tolerances(overrides or {}, expected.tolerances)
    outcome.comparison = compare(expected, got, tolerances)
    if not outcome.comparison.ok and out_dir is not None:
        plot = out_dir / path.name.replace(".golden", ".divergence.svg")
        outcome.plot = write_divergence_plot(outcome.comparison, tolerances, plot)
    return outcome


def parse_tolerance_options(atol: list[str], rtol: list[str]) -> dict[str, Tol]:
    """``--atol 1e-3`` (every field) or ``--atol pos=1e-3`` / ``--atol box.pos=1e-3`` (repeatable)."""
    from runner.errors import UsageError

    out: dict[str, dict[str, float]] = {}
    for which, items in (("atol", atol), ("rtol", rtol)):
        for item in items:
            key, sep, value = item.rpartition("=")
            key = key.strip() if sep else "default"
            try:
                number = float(value)
            except ValueError:
                raise UsageError(f"--{which} {item}: expected [FIELD=]NUMBER, e.g. 1e-4 or pos=1e-4") from None
            if not number >= 0:
                raise UsageError(f"--{which} {item}: a tolerance must be a number >= 0")
            out.setdefault(key, {})[which] = number
    return {k: Tol(v.get("atol"), v.get("rtol")) for k, v in out.items()}


def comparison_lines(comparison: Comparison, plot: Path | None = None, limit: int = 6) -> list[str]:
    """The first divergence, the other signals out of tolerance, the plot, and the notes and warnings."""
    lines: list[str] = []
    first = comparison.first
    if first is not None:
        lines.append(f"first divergence: {first.describe()}")
        over = [c for c in comparison.changes if c.first_over is not None and c.signal != first.signal]
        if over:
            more = f" and {len(over) - limit} more" if len(over) > limit else ""
            lines.append("also out of tolerance: " + ", ".join(c.describe() for c in over[:limit]) + more)
        others = [d for d in comparison.divergences[1:] if d.kind in ("event", "sound", "verdict", "run")]
        lines += [f"also: {d.describe()}" for d in others[:limit]]
    if plot is not None:
        lines.append(f"plot: {plot}")
    warning = comparison.version_warning()
    if warning:
        lines.append(f"warning: {warning}")
    lines += [f"note: {n}" for n in comparison.notes]
    return lines


def outcome_text(case: CaseOutcome, *, details: Any = None) -> str:
    """A case that did not pass, as text: its first line (the one `scenario run` gives for the same run), what
    diverged, then the verdict table; ``details``: more lines after the first (e.g. a crash's output)."""
    parts = [case.exit.headline]
    if details:
        parts.append(str(details).rstrip())
    if case.comparison is not None:
        head = "matches its baseline" if case.comparison.ok else "diverges from its baseline"
        parts.append(f"{case.label}: {head} {case.golden}")
        parts += ["  " + line for line in comparison_lines(case.comparison, case.plot)]
    if case.result is not None and case.result.verdicts:
        parts.append(verdict_text(case.result).rstrip())
    return "\n".join(parts) + "\n"
