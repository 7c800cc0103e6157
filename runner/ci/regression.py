"""Recording one case into its golden file and checking one case against it.

What `scenario baseline`, `scenario check` and the pytest plugin share. A case is recorded from the trace its
run writes (read back with :mod:`reports.trace_reader`), so a golden file holds exactly what the trace holds.
"""

from __future__ import annotations

import io
import tempfile
from dataclasses import dataclass
from pathlib import Path

from reports.trace_reader import read_trace
from runner.ci.golden import (
    DEFAULT_TOLERANCES,
    BaselineError,
    Recording,
    Tol,
    Tolerances,
    golden_name,
    read_golden,
    record_from_trace,
    sample_every,
    write_golden,
)
from runner.ci.golden_compare import Comparison, compare
from runner.ci.golden_plot import write_divergence_plot
from runner.errors import BackendError, ScenarioError, UnsupportedFeature
from runner.language.load import LoadedScenario
from runner.sim.run import run_loaded
from runner.sim.session import RunResult

PASSED, FAILURE, ERROR = "passed", "failure", "error"


@dataclass
class CaseOutcome:
    """One scenario x variant x backend checked against its golden file."""

    loaded: LoadedScenario
    backend: str
    outcome: str  # passed | failure | error
    golden: Path
    result: RunResult | None = None
    comparison: Comparison | None = None
    plot: Path | None = None
    error: str = ""  # why it is an error: no or bad baseline, engine failure
    error_kind: str = ""  # missing-baseline | bad-input | engine-failure

    @property
    def label(self) -> str:
        return f"{self.loaded.model.scenario} · {self.loaded.variant} · {self.backend}"


def golden_path(directory: Path, loaded: LoadedScenario, backend: str) -> Path:
    return directory / golden_name(loaded.model.scenario, loaded.variant, backend)


def _run_and_read(loaded: LoadedScenario, backend: str, out_dir: Path | None) -> tuple[RunResult, object | None]:
    with tempfile.TemporaryDirectory(prefix="scenario-baseline-") as tmp:
        result = run_loaded(loaded, backend, out_dir if out_dir is not None else Path(tmp))
        trace = read_trace(result.trace) if result.trace else None
    if out_dir is None:
        result.trace = None  # it was in the temporary folder
    return result, trace


def record_case(
    loaded: LoadedScenario, backend: str, directory: Path, out_dir: Path | None = None, period: float | None = None
) -> tuple[RunResult, Path, Recording]:
    """Run a case and write its golden file. An existing file keeps its tolerance lines and, unless ``period``
    is given, its sampling."""
    path = golden_path(directory, loaded, backend)
    previous = read_golden(path) if path.exists() else None
    result, trace = _run_and_read(loaded, backend, out_dir)
    if trace is None:
        raise BaselineError(f"{loaded.path}: the run of {loaded.variant} on {backend} wrote no trace to record")
    dt = loaded.model.world.dt
    if period is not None or previous is None:
        every = sample_every(dt, period)
    else:
        every = int(previous.header["every"])
    tolerances = previous.tolerances if previous is not None else dict(DEFAULT_TOLERANCES)
    rec = record_from_trace(trace, every, tolerances)
    write_golden(path, rec)
    return result, path, rec


def check_case(
    loaded: LoadedScenario,
    backend: str,
    directory: Path,
    out_dir: Path | None,
    overrides: dict[str, Tol] | None = None,
) -> CaseOutcome:
    """Run a case and compare it with its golden file; failures and errors come back in the outcome."""
    path = golden_path(directory, loaded, backend)
    if not path.exists():
        hint = f"record it with `scenario baseline {loaded.path} --backend {backend} --baseline {directory}`"
        return CaseOutcome(
            loaded, backend, ERROR, path, error=f"no baseline {path}; {hint}", error_kind="missing-baseline"
        )
    try:
        expected = read_golden(path)
    except BaselineError as exc:
        return CaseOutcome(loaded, backend, ERROR, path, error=str(exc), error_kind="bad-input")
    try:
        result, trace = _run_and_read(loaded, backend, out_dir)
    except (ScenarioError, UnsupportedFeature) as exc:  # e.g. a feature this backend lacks: the others still run
        return CaseOutcome(loaded, backend, ERROR, path, error=str(exc), error_kind="bad-input")
    except BackendError as exc:
        return CaseOutcome(loaded, backend, ERROR, path, error=str(exc), error_kind="engine-failure")
    if result.status == "engine-failure" or trace is None:
        return CaseOutcome(
            loaded,
            backend,
            ERROR,
            path,
            result,
            error=result.failure or "no trace written",
            error_kind="engine-failure",
        )
    got = record_from_trace(trace, int(expected.header["every"]))
    tolerances = Tolerances(overrides or {}, expected.tolerances)
    comparison = compare(expected, got, tolerances)
    plot = None
    if not comparison.ok and out_dir is not None:
        plot = write_divergence_plot(comparison, tolerances, out_dir / path.name.replace(".golden", ".divergence.svg"))
    outcome = PASSED if comparison.ok and result.passed else FAILURE
    return CaseOutcome(loaded, backend, outcome, path, result, comparison, plot)


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


def render(renderable: object, width: int = 120) -> str:
    """Plain text of a rich renderable (no colour, no markup), for pytest reports and JUnit files."""
    from rich.console import Console

    buf = io.StringIO()
    Console(file=buf, width=width, color_system=None, force_terminal=False, highlight=False).print(renderable)
    return buf.getvalue()


def verdict_text(result: RunResult, failures_only: bool = False) -> str:
    from rich import box

    from runner.cli.render import verdict_table

    if not result.verdicts:
        return ""
    table = verdict_table(result, failures_only)
    table.box = box.ASCII2  # plain ASCII: CI pages and JUnit viewers do not all draw box characters
    return render(table)


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


def outcome_text(case: CaseOutcome) -> str:
    """A failing or erroring case as text: what diverged, then the verdict table."""
    parts = []
    if case.error:
        parts.append(f"{case.label}: {case.error}")
    if case.comparison is not None:
        head = "matches its baseline" if case.comparison.ok else "diverges from its baseline"
        parts.append(f"{case.label}: {head} {case.golden}")
        parts += ["  " + line for line in comparison_lines(case.comparison, case.plot)]
    if case.result is not None and case.result.verdicts:
        parts.append(verdict_text(case.result).rstrip())
    return "\n".join(parts) + "\n"
