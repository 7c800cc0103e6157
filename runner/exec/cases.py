"""A case (scenario file x variant x backend x overrides), the job that runs it in a worker, and how it ended.

:class:`Case` is what travels to a worker (a local process, a Ray task); :func:`run_case` is the job
run there: it loads the scenario, runs it with :func:`runner.sim.run.run_loaded` and returns a payload
(:mod:`runner.exec.transport`: a run result, an error with its class, or an interruption).
:func:`case_result` turns the payload, or the way the worker died (:class:`runner.exec.pool.Ending`),
into a :class:`CaseResult`, whose :attr:`~CaseResult.exit` gives the exit code and the first message
line by the one mapping of :mod:`runner.exec.exits`. Whatever ran the case, the same case gives the
same :class:`CaseResult`.

A case that left no finished trace (crashed, timed out, exited, or refused after its trace folder was
chosen) gets an outcome file beside where its trace belongs (:mod:`reports.outcome`), so a report
rebuilt from the files says the same.
"""

from __future__ import annotations

import math
import signal
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from reports import outcome as oc
from reports import trace_format as tf
from runner import interrupts
from runner.errors import ExitCode, OutputError, ScenarioError, TraceError
from runner.exec import memory as mem
from runner.exec.exits import Exit, classify
from runner.exec.pool import CRASHED, EXITED, INTERRUPTED, OVER_MEMORY, RETURNED, TIMED_OUT, Ending
from runner.exec.transport import decode_error, encode_error, result_from_json, result_to_json
from runner.sim.session import RunResult
from runner.trace.output import Claim

__all__ = ["Case", "CaseResult", "Files", "case_of", "case_result", "estimate_cost", "named", "run_case"]

Files = tuple[tuple[str, bytes], ...]  # (path relative to the scenario's folder, content)


@dataclass(frozen=True)
class Case:
    """One run to make: a scenario file's variant on a backend, where its trace goes and its limits."""

    path: str  # the scenario file
    variant: str | None  # None: the base case
    backend: str
    overrides: tuple[tuple[str, Any], ...] = ()  # --set items, applied in order
    out_dir: str | None = None  # traces go here; None: no trace
    files: Files = ()  # the scenario's files, for workers that cannot read `path` (see bundle())
    cost: float = 0.0  # an estimate of the work (see estimate_cost): costly cases are started first
    record_every: int = 1  # the trace gets every k-th step (run_loaded's record_every)
    trace_process: bool = False  # the trace is written by a second process (run_loaded's trace_process)
    budget: float | None = None  # wall-clock seconds (world.budget or --timeout); the parent enforces it too
    sha256: str | None = None  # the scenario's hash when the parent loaded it: refuse a file changed since
    trace: str | None = None  # the final trace path, when out_dir is set (the parent names it)
    force: bool = False  # also replace files under the output names that this tool did not write
    scenario: str = ""  # the scenario's name (for the outcome file), when the parent loaded it
    loaded: Any = field(default=None, compare=False, repr=False)  # the LoadedScenario, when the parent has it
    #: the worker's memory ceiling in bytes (0: none), SCENARIO_MEMORY_LIMIT's where the case is made (the command,
    #: not a Ray worker)
    memory: int = field(default_factory=lambda: mem.ceiling() or 0)

    @property
    def label(self) -> str:
        return f"{Path(self.path).name} · {self.variant or 'base'} · {self.backend}"

    def bundle(self) -> Case:
        """This case carrying its scenario file and the sounds it names (for remote workers)."""
        from runner.language.load import load_scenario

        path = Path(self.path)
        loaded = load_scenario(path, self.variant, self.overrides)
        files = [(path.name, path.read_bytes())]
        files += [(str(rel), (path.parent / rel).read_bytes()) for rel in loaded.model.sounds.values()]
        # without `loaded`: the remote worker loads its own copy of the files
        return replace(self, files=tuple(files), loaded=None)


def named(case: Case) -> Case:
    """``case`` with its final trace path and scenario name filled in (loading the scenario here when the
    caller did not name them), so that this process can own its output names."""
    if case.out_dir is None or case.trace is not None:
        return case
    from runner.language.load import load_scenario
    from runner.sim.run import trace_path

    try:
        loaded = load_scenario(Path(case.path), case.variant, case.overrides)
    except Exception:  # noqa: BLE001 - the worker meets the same error and reports it with its class
        return case
    return replace(case, trace=str(trace_path(Path(case.out_dir), loaded, case.backend)),
                   scenario=case.scenario or loaded.model.scenario)  # fmt: skip


def case_of(loaded: Any, backend: str, out_dir: Path | None, budget: float | None = None) -> Case:
    """The case that runs ``loaded`` (a LoadedScenario) on ``backend`` as `scenario run` does: its trace in
    ``out_dir`` (None: no trace), stopped after ``budget`` seconds (default: world.budget, else one hour)."""
    from runner.language.load import BASE_CASE
    from runner.sim.budget import DEFAULT_BUDGET
    from runner.sim.run import trace_path

    limit = budget if budget is not None else (loaded.model.world.budget or DEFAULT_BUDGET)
    return Case(
        str(loaded.path), None if loaded.variant == BASE_CASE else loaded.variant, backend, loaded.overrides,
        None if out_dir is None else str(out_dir), cost=estimate_cost(loaded), budget=limit, sha256=loaded.sha256,
        trace=None if out_dir is None else str(trace_path(out_dir, loaded, backend)),
        scenario=loaded.model.scenario, loaded=loaded,
    )  # fmt: skip


def estimate_cost(loaded: Any) -> float:
    """Steps x bodies x substeps of a loaded case: the order to start cases in (longest first keeps the
    last worker from finishing alone)."""
    from runner.language.names import expand_bodies

    world = loaded.model.world
    return math.floor(world.duration / world.dt + 0.5) * (len(expand_bodies(loaded.model)) + 1) * world.substeps


# ---- in the worker ------------------------------------------------------------------------------


def run_case(case: Case, report: Any = None) -> dict[str, Any]:
    """The job: run ``case`` here and return its payload. Signals are held from the start (an interruption
    during the engine's import or the world's build is an interruption, checked when they return)."""
    from runner.language.load import load_scenario
    from runner.sim.run import run_loaded

    start = time.perf_counter()
    with interrupts.deferred(check_at_exit=False):
        try:
            path = Path(case.path)
            loaded = case.loaded if case.loaded is not None else load_scenario(path, case.variant, case.overrides)
            if case.sha256 is not None and loaded.sha256 != case.sha256:
                raise ScenarioError(f"{path} changed after it was loaded; run again")
            interrupts.check()
            out_dir = None if case.out_dir is None else Path(case.out_dir)
            result = run_loaded(loaded, case.backend, out_dir, report, force=case.force, record_every=case.record_every,
                                trace_process=case.trace_process, budget=case.budget)  # fmt: skip
        except KeyboardInterrupt as exc:
            return {"status": "interrupted", "signal": interrupts.signal_of(exc),
                    "wall_seconds": time.perf_counter() - start}  # fmt: skip
        except Exception as exc:  # noqa: BLE001 - every error crosses to the parent with its class
            wrapped = interrupts.behind(exc)  # an interruption something wrapped while it was raised
            if wrapped is not None:
                return {"status": "interrupted", "signal": interrupts.signal_of(wrapped),
                        "wall_seconds": time.perf_counter() - start}  # fmt: skip
            return {"status": "error", "error": encode_error(exc), "wall_seconds": time.perf_counter() - start}
    return {"status": "completed", "result": result_to_json(result), "wall_seconds": time.perf_counter() - start}


# ---- in the parent ------------------------------------------------------------------------------

ERROR, TIMED_OUT_STATUS = "error", "timed-out"
OUTCOME_TAIL = 2000  # characters of a crashed engine's output kept in its outcome file


@dataclass
class CaseResult:
    """How a case ended: its status, its result or error, and its trace."""

    case: Case
    status: str  # passed | failed | engine-failure | error | crashed | timed-out | over-memory | exited | interrupted
    result: RunResult | None = None  # when the run completed (passed, failed, engine-failure)
    error: BaseException | None = None  # for "error": the exception, rebuilt with its class
    signal: int | None = None  # the signal that ended the worker, if one did
    returncode: int | None = None
    trace: str | None = None  # the finished trace, or the .partial one a crash or a full disk left
    outcome_file: str | None = None
    output: str = ""  # what the engine printed while running the case
    timeout: float | None = None
    written: dict[str, bytes] = field(default_factory=dict)  # files a remote run wrote, by name
    wall_seconds: float = 0.0  # never in tables or traces
    memory: int | None = None  # over-memory: the ceiling (bytes)
    peak: int | None = None  # over-memory: the worker's resident memory at its last reading (bytes)
    progress: tuple[int, int] | None = None  # over-memory: the last (steps done, steps in all) it reported

    @property
    def passed(self) -> bool:
        return self.status == "passed"

    @property
    def exit(self) -> Exit:
        """The exit code and first message line (runner.exec.exits): the same for this case on every path."""
        if self.result is not None:
            r = self.result
            if r.status == "passed":
                return Exit(ExitCode.OK, "passed", "")
            if r.status == "failed":
                failed = [v.name for v in r.verdicts if not v.passed]
                return Exit(ExitCode.ASSERTION_FAILED, "failed",
                            f"{len(failed)} of {len(r.verdicts)} assertions: {', '.join(failed)}")  # fmt: skip
            return Exit(ExitCode.ENGINE_FAILURE, "engine failure", r.failure or r.status)
        if self.status == ERROR and self.error is not None:
            return classify(self.error)
        if self.status == CRASHED:
            if self.signal is None:  # a Ray worker lost with its node: no signal to name
                return Exit(ExitCode.ENGINE_FAILURE, "crashed", _last_line(self.output))
            name = signal.Signals(self.signal).name if self.signal in signal.valid_signals() else "a signal"
            return Exit(ExitCode.ENGINE_FAILURE, f"crashed (signal {self.signal})",
                        _last_line(self.output) or f"the process running the engine was killed by {name}")  # fmt: skip
        if self.status == TIMED_OUT_STATUS:
            stopped = f"; stopped by signal {self.signal}" if self.signal is not None else ""
            return Exit(ExitCode.ENGINE_FAILURE, "timed out",
                        f"no result after {self.timeout:g} s (world.budget, or --timeout){stopped}")  # fmt: skip
        if self.status == OVER_MEMORY:
            return Exit(ExitCode.ENGINE_FAILURE, "over memory", _over_memory(self))
        if self.status == INTERRUPTED:
            code = ExitCode.TERMINATED if self.signal == signal.SIGTERM else ExitCode.INTERRUPTED
            return Exit(code, "terminated" if code is ExitCode.TERMINATED else "interrupted", "")
        return Exit(ExitCode.ENGINE_FAILURE, f"exited with code {self.returncode}",
                    _last_line(self.output) or "the process running the engine ended without a result")  # fmt: skip

    @property
    def label(self) -> str:
        """The status as a report shows it: "passed", "engine failure", "crashed (signal 6)", "error", ..."""
        return self.exit.label

    @property
    def headline(self) -> str:
        return self.exit.headline

    @property
    def failure(self) -> str | None:
        """What stopped the case: a completed run's engine failure, else the message of how it ended."""
        if self.result is not None:
            return self.result.failure
        return self.exit.message or self.exit.label

    @property
    def error_type(self) -> str | None:
        return None if self.error is None else type(self.error).__name__

    def raise_error(self) -> None:
        """Raise the exception that made this an ``error`` again (its own class), else nothing."""
        if self.error is not None:
            raise self.error


def _over_memory(res: CaseResult) -> str:
    """The first line names the ceiling and where it comes from (the same on every path); the second what was
    measured, which varies with the moment of the reading."""
    limit = f"{(res.memory or 0) / mem.MIB:g} MiB"
    held = f"{(res.peak or 0) / mem.MIB:.0f} MiB" if res.peak else "more"
    when = (f"after step {res.progress[0]} of {res.progress[1]} (as last reported)" if res.progress
            else "before its first step (loading the scenario or building the world)")  # fmt: skip
    return (f"the worker went over its memory ceiling of {limit} ({mem.ENV}; docs/reliability.md); "
            f"stopped by signal 9\nit held {held} {when}")  # fmt: skip


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.strip().splitlines() if line.strip()]
    return lines[-1] if lines else ""


def _kept_trace(case: Case) -> str | None:
    if case.trace is None:
        return None
    final = Path(case.trace)
    partial = final.with_name(final.name + tf.PARTIAL_SUFFIX)
    return str(final) if final.is_file() else str(partial) if partial.is_file() else None


def case_result(case: Case, ending: Ending) -> CaseResult:
    """How ``case`` ended, from its payload or its worker's death; writes its outcome file if it needs one."""
    payload = ending.payload or {}
    status = str(payload.get("status", ""))
    wall = float(payload.get("wall_seconds", ending.wall_seconds))
    res = CaseResult(case, ERROR, output=ending.output, timeout=ending.timeout, wall_seconds=wall,
                     signal=ending.signal, returncode=ending.returncode)  # fmt: skip
    if ending.how == RETURNED and status == "completed":
        res.result = result_from_json(payload["result"])
        res.status = res.result.status
    elif ending.how == RETURNED and status == "error":
        res.error = decode_error(payload["error"])
    elif ending.how in (RETURNED, INTERRUPTED) and (status == "interrupted" or ending.how == INTERRUPTED):
        res.status = INTERRUPTED
        res.signal = int(payload.get("signal", ending.signal or signal.SIGINT))
    elif ending.how == TIMED_OUT:
        res.status = TIMED_OUT_STATUS
    elif ending.how == OVER_MEMORY:
        res.status, res.memory, res.peak, res.progress = OVER_MEMORY, ending.memory, ending.peak, ending.progress
    elif ending.how == CRASHED:
        res.status = CRASHED
    elif ending.how == EXITED or ending.how == RETURNED:
        res.status = EXITED
    refused = isinstance(res.error, TraceError) and not isinstance(res.error, OutputError)
    res.trace = None if refused else _kept_trace(case)  # refused for its outputs: what is there is not its own
    if res.result is not None and res.trace is not None:
        res.result.trace = res.trace
    if ending.how != RETURNED or _wants_outcome(res):
        _tidy(res)
    return res


def _wants_outcome(res: CaseResult) -> bool:
    """The case's trace cannot tell how it ended (there is none, or only a ``.partial``)."""
    finished = res.trace is not None and not res.trace.endswith(tf.PARTIAL_SUFFIX)
    refused = isinstance(res.error, TraceError) and not isinstance(res.error, OutputError)
    wanted = res.status in (CRASHED, TIMED_OUT_STATUS, OVER_MEMORY, EXITED) or (res.status == ERROR and not finished)
    return res.case.trace is not None and wanted and not refused  # refused for its outputs: write nothing there


def _tidy(res: CaseResult) -> None:
    """After the case's worker is gone: take the case's names again (without clearing what it left), add
    the outcome file if the trace cannot tell, and release them (a lock file a killed worker left is
    removed). If another run has taken the names meanwhile, its files are left alone."""
    if res.case.trace is None:
        return
    try:
        claim = Claim(Path(res.case.trace), clear=False)
    except TraceError:
        return
    with claim:
        if _wants_outcome(res):
            _write_outcome_file(res, Path(res.case.trace))


def _write_outcome_file(res: CaseResult, trace: Path) -> None:
    case = res.case
    from backends.registry import engine_version

    exit = res.exit
    outcome = {CRASHED: oc.CRASHED, TIMED_OUT_STATUS: oc.TIMED_OUT, OVER_MEMORY: oc.OVER_MEMORY,
               EXITED: oc.EXITED}.get(res.status, oc.ERROR)  # fmt: skip
    record = oc.RunOutcome(
        scenario=res.result.scenario if res.result is not None else case.scenario,
        variant=case.variant or "base",
        backend=case.backend,
        backend_version=engine_version(case.backend),
        outcome=outcome,
        signal=res.signal,
        returncode=res.returncode,
        timeout=res.timeout if res.status == TIMED_OUT_STATUS else None,
        message=exit.message if res.status in (ERROR, OVER_MEMORY) else res.output.strip()[-OUTCOME_TAIL:],
        trace=Path(res.trace).name if res.trace is not None else None,
    )
    try:
        res.outcome_file = str(oc.write_outcome(oc.outcome_path(trace), record))
    except OSError:  # a full disk: the exit code already says so, and write_outcome left nothing behind
        res.outcome_file = None
