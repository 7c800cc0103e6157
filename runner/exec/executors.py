"""Running many cases (file x variant x backend x parameter set) elsewhere: local worker processes or Ray.

Every executor runs each case in a worker process through the one protocol of :mod:`runner.exec.pool`
and :mod:`runner.exec.cases`, and returns one :class:`~runner.exec.cases.CaseResult` per case, in the
order given, whatever order they finish in:

* :class:`LocalExecutor`: ``jobs`` worker processes (``jobs == 1``: the serial path, one worker reused
  from case to case); ``isolate`` gives every case a process of its own. A case whose engine kills its
  process is ``crashed (signal N)``, one over its budget ``timed out``; the other cases go on.
* :class:`RayExecutor` (extra ``ray``): each case is a Ray task that runs the same local protocol inside
  the Ray worker, so a crash is still ``crashed (signal N)`` with its ``.partial`` trace, and a budget
  still holds. The scenario file and its sounds travel with the task and every file the run wrote comes
  back, so workers need no shared file system.

Each case's output names are owned for the whole case (:class:`runner.trace.output.Claim`: taken by the
worker that writes them, or by this process for a Ray task, whose files it writes when they come back):
a concurrent run for the same names fails at once with exit 2 and never damages this one.

Results are deterministic: the same cases give the same results and byte-identical traces whichever
executor runs them (wall time stays out of them, in ``CaseResult.wall_seconds`` and the ``.cost.json``).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import tempfile
from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, Protocol

from reports import trace_format as tf
from runner.errors import ExitCode, TraceError, UsageError
from runner.exec.cases import Case, CaseResult, case_result, estimate_cost, named, run_case
from runner.exec.exits import most_severe
from runner.exec.pool import RETURNED, TIMEOUT_GRACE, Ending, Job, Pool
from runner.exec.transport import encode_error
from runner.trace.output import Claim, foreign, publish_trace, refusal, write_error

__all__ = [
    "EXECUTORS",
    "Case",
    "CaseResult",
    "Executor",
    "LocalExecutor",
    "OnProgress",
    "OnResult",
    "RayExecutor",
    "add_arguments",
    "check_outputs",
    "estimate_cost",
    "make_executor",
    "status_code",
]

EXECUTORS = ("local", "ray")
RAY_HINT = "pip install 'physics-scenarios[ray]'"
OnResult = Callable[[int, CaseResult], None]
OnProgress = Callable[[int, int, int], None]  # (case index, steps done, steps in all)


class Executor(Protocol):
    """Runs cases and returns their results in the order given (see the module docstring)."""

    def run(self, cases: Sequence[Case], on_result: OnResult | None = None,
            on_progress: OnProgress | None = None) -> list[CaseResult]: ...  # fmt: skip

    def close(self) -> None: ...


def check_outputs(cases: Iterable[Case], force: bool = False) -> None:
    """Refuse, before anything runs, to overwrite files under these cases' output names that this tool did
    not write (``--force`` allows it); the tool's own earlier outputs are replaced without asking."""
    if force:
        return
    left = foreign(Path(c.trace) for c in cases if c.trace is not None)
    if left:
        raise TraceError(refusal(left))


def _refused(exc: BaseException) -> Ending:
    return Ending(RETURNED, {"status": "error", "error": encode_error(exc)})


class _Claims:
    """The output names of the cases in flight, held by this process."""

    def __init__(self, cases: Sequence[Case], force: bool) -> None:
        self.cases = cases
        self.force = force
        self.held: dict[int, Claim] = {}

    def take(self, index: int) -> Ending | None:
        trace = self.cases[index].trace
        if trace is None:
            return None
        try:
            self.held[index] = Claim(Path(trace), force=self.force)
        except TraceError as exc:
            return _refused(exc)
        return None

    def release(self, index: int) -> None:
        claim = self.held.pop(index, None)
        if claim is not None:
            claim.release()

    def release_all(self) -> None:
        for index in list(self.held):
            self.release(index)


class LocalExecutor:
    """``jobs`` worker processes on this machine (see the module docstring)."""

    def __init__(self, jobs: int = 1, *, isolate: bool = False, force: bool = False,
                 grace: float = TIMEOUT_GRACE) -> None:  # fmt: skip
        if jobs < 1:
            raise UsageError(f"Invalid `-j`. Expected a positive number of processes. Received: {jobs}")
        self.jobs = jobs
        self.isolate = isolate
        self.force = force
        self.grace = grace  # seconds between a time limit's SIGTERM and SIGKILL

    def run(self, cases: Sequence[Case], on_result: OnResult | None = None,
            on_progress: OnProgress | None = None) -> list[CaseResult]:  # fmt: skip
        cases = [replace(named(c), force=c.force or self.force) for c in cases]
        results: dict[int, CaseResult] = {}

        def end(index: int, ending: Ending) -> None:
            results[index] = case_result(cases[index], ending)
            if on_result is not None:
                on_result(index, results[index])

        jobs = [Job(run_case, (c,), c.backend, c.budget, self.isolate, c.cost) for c in cases]
        with Pool(min(self.jobs, max(1, len(cases))), timeout_grace=self.grace) as pool:
            pool.run(jobs, end, on_progress)
        return [results[i] for i in range(len(cases))]

    def close(self) -> None:
        """Nothing stays running between run() calls."""


# --- Ray ----------------------------------------------------------------------------------------------


def ray_task(case: Case) -> dict[str, Any]:
    """In a Ray worker: ``case`` (bundled) run by the local protocol in a child process, and the files it
    wrote. Returns the ending and the files as plain data."""
    with tempfile.TemporaryDirectory(prefix="scenario-ray-") as tmp:
        src = Path(tmp, "src")
        for rel, data in case.files:
            target = src / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        out = Path(tmp, "out")
        local = Case(str(src / case.files[0][0]), case.variant, case.backend, case.overrides,
                     None if case.out_dir is None else str(out), (), case.cost, case.record_every,
                     case.trace_process, case.budget, case.sha256)  # fmt: skip
        with Pool(1) as pool:
            (ending,) = pool.run([Job(run_case, (local,), case.backend, case.budget, True, case.cost)])
        written = {f.name: f.read_bytes() for f in sorted(out.iterdir()) if f.is_file()} if out.is_dir() else {}
    return {"ending": ending, "written": written}


class RayExecutor:
    """Cases as Ray tasks (one CPU each) on the cluster at ``address`` ("auto", "ray://host:10001"), or on
    a local instance started here (``address=None``; ``jobs`` CPUs, default all). At most ``jobs`` tasks
    are in flight when ``jobs`` is given. ``runtime_env`` is passed to ``ray.init`` (e.g. py_modules).
    An interrupted run cancels its tasks: their traces stay on the workers' temporary folders."""

    def __init__(self, address: str | None = None, jobs: int | None = None,
                 runtime_env: dict[str, Any] | None = None, *, force: bool = False) -> None:  # fmt: skip
        try:
            import ray
        except ImportError as exc:
            raise UsageError(f"`--executor ray` needs Ray (not installed); install it with: {RAY_HINT}") from exc
        self._ray = ray
        self.jobs = jobs
        self.force = force
        self._started = not ray.is_initialized()
        if self._started:
            import logging

            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
            kwargs["logging_level"] = logging.ERROR
            if runtime_env:
                kwargs["runtime_env"] = runtime_env
            if address is None:
                kwargs["num_cpus"] = jobs or os.cpu_count() or 1
            try:
                ray.init(address=address, **kwargs)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                raise UsageError(f"cannot reach the Ray cluster at `{address}`: {exc}") from exc
        self._task = ray.remote(num_cpus=1, max_retries=0)(ray_task)

    def run(self, cases: Sequence[Case], on_result: OnResult | None = None,
            on_progress: OnProgress | None = None) -> list[CaseResult]:  # fmt: skip
        ray = self._ray
        cases = [named(c) for c in cases]
        stack = list(reversed(sorted(range(len(cases)), key=lambda i: (-cases[i].cost, i))))
        limit = self.jobs or len(cases) or 1
        claims = _Claims(cases, self.force)
        flight: dict[Any, int] = {}
        done: dict[int, CaseResult] = {}

        def finish(index: int, ending: Ending) -> None:
            claims.release(index)  # the files are in place: the outcome file, if any, is written under a new claim
            done[index] = case_result(cases[index], ending)
            if on_result is not None:
                on_result(index, done[index])

        try:
            while stack or flight:
                while stack and len(flight) < limit:
                    index = stack.pop()
                    refused = claims.take(index)
                    if refused is not None:
                        finish(index, refused)
                        continue
                    flight[self._task.remote(cases[index].bundle())] = index
                if not flight:
                    continue
                ready, _ = ray.wait(list(flight), num_returns=1)
                for ref in ready:
                    index = flight.pop(ref)
                    finish(index, self._collect(ref, cases[index]))
        except BaseException:
            for ref in flight:
                ray.cancel(ref, force=True)
            raise
        finally:
            claims.release_all()
        return [done[i] for i in range(len(cases))]

    def _collect(self, ref: Any, case: Case) -> Ending:
        """The task's ending, its files put in place (this process holds the case's names)."""
        ray = self._ray
        try:
            reply: dict[str, Any] = ray.get(ref)
        except ray.exceptions.RayTaskError:  # ray_task reports every error of the case: this is a bug in it
            raise
        except ray.exceptions.RayError as exc:  # the Ray worker, its raylet or its node died: not the engine's doing
            return Ending("crashed", None, output=f"the Ray worker running the case was lost: {exc}")
        if case.out_dir is not None:
            try:
                _publish(Path(case.out_dir), reply["written"])
            except TraceError as exc:  # a full disk here is the case's output error, as in a local run
                return _refused(exc)
        ending: Ending = reply["ending"]
        return ending

    def close(self) -> None:
        if self._started and self._ray.is_initialized():
            self._ray.shutdown()


def _publish(out: Path, written: dict[str, bytes]) -> None:
    """Files a remote run wrote, put in ``out`` (whose names this process owns) as a local run writes them:
    the trace first, through its ``.partial`` name (runner.trace.output.publish_trace), then the others
    each under a temporary name and renamed."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise write_error(exc, f"into {out}") from exc
    traces = [n for n in written if n.endswith((tf.FILE_SUFFIX, tf.FILE_SUFFIX + tf.PARTIAL_SUFFIX))]
    for name in traces:
        publish_trace(out / name, written[name])
    for name in sorted(set(written) - set(traces)):
        target, tmp = out / name, out / f"{name}.partial"
        try:
            tmp.write_bytes(written[name])
            os.replace(tmp, target)
        except OSError as exc:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise write_error(exc, str(target)) from exc


def make_executor(kind: str = "local", jobs: int = 1, ray_address: str | None = None, *, isolate: bool = False,
                  force: bool = False) -> Executor:  # fmt: skip
    """The executor a command asked for (``--executor``, ``-j``, ``--ray-address``, ``--isolate``)."""
    if kind == "local":
        if ray_address:
            raise UsageError("`--ray-address` needs `--executor ray`")
        return LocalExecutor(jobs, isolate=isolate, force=force)
    if kind == "ray":
        return RayExecutor(ray_address, jobs if jobs > 1 else None, force=force)
    raise UsageError(f"Invalid `--executor`. Expected one of {', '.join(EXECUTORS)}. Received: {kind}")


def add_arguments(parser: argparse.ArgumentParser, jobs_default: int = 1) -> None:
    """``-j``, ``--executor`` and ``--ray-address``, for the commands that run many cases."""
    parser.add_argument("-j", "--jobs", type=int, default=jobs_default, metavar="N",
                        help=f"cases run in parallel (default {jobs_default})")  # fmt: skip
    parser.add_argument("--executor", choices=EXECUTORS, default="local",
                        help="local process pool (default) or a Ray cluster (extra `ray`)")  # fmt: skip
    parser.add_argument("--ray-address", metavar="ADDR",
                        help="a Ray cluster (`auto`, `ray://host:10001`); default: start a local one")  # fmt: skip


def status_code(results: Sequence[CaseResult]) -> ExitCode:
    """The exit code for a batch: the most severe of its cases' codes (runner.exec.exits.SEVERITY)."""
    return most_severe(r.exit.code for r in results)
