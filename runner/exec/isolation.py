"""Run one case in a child process, so that an engine that segfaults or hangs cannot take the caller down.

``run_isolated(loaded, backend, out_dir, timeout=...)`` starts ``python -m runner.exec.isolation`` for one
scenario variant on one backend (``out_dir=None``: no trace). The child reloads the scenario (path,
variant, overrides; it refuses a file whose hash changed since the parent loaded it), runs it with
:func:`runner.sim.run.run_loaded` and hands back the :class:`~runner.sim.session.RunResult` as JSON through a
file. The parent returns an :class:`IsolatedRun` whose ``outcome`` is ``completed`` (``result`` is set;
the run itself may have passed, failed or met an engine failure) or one of
:data:`reports.outcome.OUTCOMES`:

* ``crashed``: killed by a signal (``signal`` set): "crashed (signal 11)";
* ``timed-out``: no result within ``timeout`` s; the child gets SIGTERM (it finishes its trace, marked
  interrupted) and, ``grace`` s later, SIGKILL;
* ``error`` (bad input, missing engine, unsupported feature: ``message``), ``exited`` (a non-zero exit
  without a result), ``interrupted`` (SIGINT/SIGTERM from outside).

Every trace written is kept: ``trace`` is the finished ``.mcap`` or the ``.partial`` one a crash left
(readable with ``reports.trace_reader.read_trace(path, recover=True)``). For any outcome but
``completed`` an outcome file (:mod:`reports.outcome`) is written beside the trace, so reports rebuilt
from files say the same. A case's earlier trace, partial trace, cost and outcome files are removed first.
``run_many`` runs cases in parallel threads, each driving one child, and returns results in order.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time as wallclock
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, fields, replace
from pathlib import Path
from types import FrameType
from typing import Any

from reports import outcome as oc
from reports.trace_format import PARTIAL_SUFFIX
from runner.language.load import LoadedScenario
from runner.sim.assertions import Verdict
from runner.sim.session import RunResult

__all__ = ["COMPLETED", "IsolatedRun", "run_isolated", "run_many"]

COMPLETED = "completed"
DEFAULT_GRACE = 5.0  # seconds between SIGTERM and SIGKILL for a run past its time limit
_TAIL = 2000  # characters of the child's output kept for a failure message

_EXIT_RESULT, _EXIT_BAD_INPUT, _EXIT_ENGINE, _EXIT_INTERRUPTED = 0, 2, 3, 130


@dataclass(frozen=True)
class IsolatedRun:
    scenario: str
    variant: str
    backend: str
    outcome: str  # COMPLETED or one of reports.outcome.OUTCOMES
    result: RunResult | None = None  # set when completed
    trace: Path | None = None  # the finished trace, or the .partial one a crash left
    outcome_file: Path | None = None
    returncode: int | None = None
    signal: int | None = None
    message: str = ""
    wall_seconds: float = 0.0  # the child's lifetime, for the terminal only (never in a report)

    @property
    def completed(self) -> bool:
        return self.outcome == COMPLETED

    @property
    def label(self) -> str:
        """The run's status ("passed", "failed", "engine-failure") or how it ended ("crashed (signal 11)")."""
        if self.result is not None:
            return self.result.status
        return self._as_outcome().label

    def _as_outcome(self, timeout: float | None = None, version: str = "") -> oc.RunOutcome:
        return oc.RunOutcome(
            scenario=self.scenario,
            variant=self.variant,
            backend=self.backend,
            backend_version=version,
            outcome=self.outcome,
            signal=self.signal,
            returncode=self.returncode,
            timeout=timeout,
            message=self.message,
            trace=self.trace.name if self.trace is not None else None,
        )


def _expected_trace(loaded: LoadedScenario, backend: str, out_dir: Path) -> Path:
    from runner.sim.run import trace_path

    return trace_path(out_dir, loaded, backend)


def _remove_stale(trace: Path) -> None:
    for path in (trace, trace.with_name(trace.name + PARTIAL_SUFFIX), oc.outcome_path(trace), oc.cost_path(trace)):
        if path.exists():
            path.unlink()


def _result_from_json(data: dict[str, Any]) -> RunResult:
    names = {f.name for f in fields(Verdict)}
    verdicts = [Verdict(**{k: v for k, v in d.items() if k in names}) for d in data["verdicts"]]
    return RunResult(
        scenario=data["scenario"],
        variant=data["variant"],
        backend=data["backend"],
        status=data["status"],
        verdicts=verdicts,
        end_time=data["end_time"],
        steps=data["steps"],
        events=[(float(t), str(n), str(s)) for t, n, s in data["events"]],
        sounds=[(float(t), str(n)) for t, n in data["sounds"]],
        wall_seconds=data["wall_seconds"],
        trace=data["trace"],
        failure=data["failure"],
        extra=data["extra"],
    )


def _result_to_json(result: RunResult) -> dict[str, Any]:
    return {
        "scenario": result.scenario,
        "variant": result.variant,
        "backend": result.backend,
        "status": result.status,
        "verdicts": [v.as_dict() for v in result.verdicts],
        "end_time": result.end_time,
        "steps": result.steps,
        "events": [list(e) for e in result.events],
        "sounds": [list(s) for s in result.sounds],
        "wall_seconds": result.wall_seconds,
        "trace": result.trace,
        "failure": result.failure,
        "extra": result.extra,
    }


# ---- the parent ---------------------------------------------------------------------------------

_live: set[subprocess.Popen[bytes]] = set()
_live_lock = threading.Lock()


def _stop_all(grace: float) -> None:
    """Stop every child still running (the caller was interrupted): SIGTERM, then SIGKILL."""
    with _live_lock:
        procs = list(_live)
    for proc in procs:
        if proc.poll() is None:
            proc.terminate()
    deadline = wallclock.monotonic() + grace
    for proc in procs:
        try:
            proc.wait(timeout=max(0.0, deadline - wallclock.monotonic()))
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _tail(data: bytes) -> str:
    text = data.decode("utf-8", errors="replace").strip()
    return text[-_TAIL:]


@dataclass(frozen=True)
class _Exit:
    returncode: int
    output: bytes
    payload: dict[str, Any]
    timed_out: bool
    wall_seconds: float


def _spawn(spec: dict[str, Any], timeout: float | None, grace: float) -> _Exit:
    """Start the child, wait up to ``timeout`` (then SIGTERM, ``grace``, SIGKILL) and collect what it left."""
    with tempfile.TemporaryDirectory(prefix="scenario-isolated-") as tmp:
        result_file = Path(tmp) / "result.json"
        cmd = [sys.executable, "-m", "runner.exec.isolation", json.dumps(spec, default=str), str(result_file)]
        start = wallclock.monotonic()
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        with _live_lock:
            _live.add(proc)
        timed_out = False
        try:
            try:
                output, _ = proc.communicate(timeout=timeout)
            except subprocess.TimeoutExpired:
                timed_out = True
                proc.terminate()
                try:
                    output, _ = proc.communicate(timeout=grace)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    output, _ = proc.communicate()
        finally:
            with _live_lock:
                _live.discard(proc)
        wall = wallclock.monotonic() - start
        payload: dict[str, Any] = {}
        if result_file.exists():
            try:
                payload = json.loads(result_file.read_text(encoding="utf-8"))
            except (OSError, json.JSONDecodeError):
                payload = {}
    return _Exit(proc.returncode, output or b"", payload, timed_out, wall)


def run_isolated(
    loaded: LoadedScenario,
    backend: str,
    out_dir: Path | None,
    *,
    timeout: float | None = None,
    grace: float = DEFAULT_GRACE,
) -> IsolatedRun:
    """Run ``loaded`` on ``backend`` in a child process, writing its trace into ``out_dir`` (None: no
    trace, and no outcome file)."""
    if timeout is not None and not (timeout > 0 and math.isfinite(timeout)):
        raise ValueError(f"Invalid `timeout`. Expected a positive number of seconds. Received: {timeout!r}")
    trace: Path | None = None
    if out_dir is not None:
        out_dir = Path(out_dir).resolve()
        out_dir.mkdir(parents=True, exist_ok=True)
        trace = _expected_trace(loaded, backend, out_dir)
        _remove_stale(trace)
    spec = {
        "path": str(Path(loaded.path).resolve()),
        "variant": loaded.variant,
        "overrides": [list(o) for o in loaded.overrides],
        "sha256": loaded.sha256,
        "backend": backend,
        "out_dir": None if out_dir is None else str(out_dir),
    }
    done = _spawn(spec, timeout, grace)
    rc, payload = done.returncode, done.payload
    kept = None
    if trace is not None:
        partial = trace.with_name(trace.name + PARTIAL_SUFFIX)
        kept = trace if trace.exists() else partial if partial.exists() else None
    run = IsolatedRun(
        scenario=loaded.model.scenario,
        variant=loaded.variant,
        backend=backend,
        outcome=oc.EXITED,
        trace=kept,
        returncode=rc,
        signal=-rc if rc < 0 else None,
        message=_tail(done.output),
        wall_seconds=done.wall_seconds,
    )
    if done.timed_out:
        run = replace(run, outcome=oc.TIMED_OUT)
    elif "result" in payload:
        return replace(run, outcome=COMPLETED, result=_result_from_json(payload["result"]), message="")
    elif rc < 0:
        run = replace(run, outcome=oc.CRASHED)
    elif "error" in payload:
        run = replace(run, outcome=oc.ERROR, message=str(payload["error"]))
    elif "interrupted" in payload:
        run = replace(run, outcome=oc.INTERRUPTED, message=str(payload["interrupted"]))
    if trace is None:
        return run
    from backends.registry import engine_version

    limit = timeout if run.outcome == oc.TIMED_OUT else None
    path = oc.write_outcome(oc.outcome_path(trace), run._as_outcome(limit, engine_version(backend)))
    return replace(run, outcome_file=path)


def run_many(
    cases: Sequence[tuple[LoadedScenario, str]],
    out_dir: Path | None,
    *,
    jobs: int = 1,
    timeout: float | None = None,
    grace: float = DEFAULT_GRACE,
    on_done: Callable[[IsolatedRun], None] | None = None,
) -> list[IsolatedRun]:
    """Run each (case, backend) isolated, up to ``jobs`` at a time; results in the order of ``cases``.

    If the caller is interrupted (Ctrl-C, SIGTERM raised as KeyboardInterrupt), every child still
    running is stopped with SIGTERM, so its trace is finished and marked interrupted, then SIGKILL.
    """
    if jobs < 1:
        raise ValueError(f"Invalid `jobs`. Expected an integer >= 1. Received: {jobs!r}")

    stopping = threading.Event()

    def one(case: tuple[LoadedScenario, str]) -> IsolatedRun:
        if stopping.is_set():
            raise KeyboardInterrupt("stopped before it started")
        run = run_isolated(case[0], case[1], out_dir, timeout=timeout, grace=grace)
        if on_done is not None:
            on_done(run)
        return run

    pool = ThreadPoolExecutor(max_workers=jobs, thread_name_prefix="isolated-run")
    futures = []
    try:
        futures = [pool.submit(one, case) for case in cases]
        return [f.result() for f in futures]
    except BaseException:
        stopping.set()
        for f in futures:
            f.cancel()
        _stop_all(grace)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


# ---- the child ----------------------------------------------------------------------------------


class _Terminated(KeyboardInterrupt):
    """SIGTERM in the child: finish the trace as interrupted, like Ctrl-C."""


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    raise _Terminated("SIGTERM")


def _write(path: Path, payload: dict[str, Any]) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(payload, default=str), encoding="utf-8")
    os.replace(tmp, path)


def _child(spec: dict[str, Any], result_file: Path) -> int:
    from backends.errors import BackendError, UnknownBackend, UnsupportedFeature
    from runner.errors import PhysicsScenariosError, ScenarioError, ScenarioValidationError
    from runner.language.load import load_scenario
    from runner.sim.run import run_loaded

    signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        overrides = tuple((str(k), v) for k, v in spec["overrides"])
        loaded = load_scenario(Path(spec["path"]), spec["variant"], overrides)
        if loaded.sha256 != spec["sha256"]:
            _write(result_file, {"error": f"{spec['path']} changed after it was loaded; run again"})
            return _EXIT_BAD_INPUT
        out_dir = None if spec["out_dir"] is None else Path(spec["out_dir"])
        result = run_loaded(loaded, spec["backend"], out_dir)
    except ScenarioValidationError as exc:
        _write(result_file, {"error": "\n".join(str(i) for i in exc.issues)})
        return _EXIT_BAD_INPUT
    except (ScenarioError, UnknownBackend, UnsupportedFeature) as exc:
        _write(result_file, {"error": str(exc)})
        return _EXIT_BAD_INPUT
    except (BackendError, PhysicsScenariosError) as exc:
        _write(result_file, {"error": str(exc)})
        return _EXIT_ENGINE
    except KeyboardInterrupt as exc:
        _write(result_file, {"interrupted": "SIGTERM" if isinstance(exc, _Terminated) else "SIGINT"})
        return _EXIT_INTERRUPTED
    _write(result_file, {"result": _result_to_json(result)})
    return _EXIT_RESULT


def main(argv: Sequence[str]) -> int:
    if len(argv) != 2:
        sys.stderr.write("usage: python -m runner.exec.isolation SPEC_JSON RESULT_FILE (used by scenario compare)\n")
        return 2
    return _child(json.loads(argv[0]), Path(argv[1]))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
