"""Cases as Ray tasks: the same local protocol inside each Ray worker, files carried both ways.

Each case is a Ray task (1 CPU) that runs :func:`ray_task`: the scenario file and its sounds travel with
the task, the case runs in a child process of the Ray worker by :mod:`runner.exec.pool` (a crash of the
engine is ``crashed (signal N)`` with its ``.partial`` trace, as locally; the budget holds), and every
file the run wrote comes back. This process owns the case's output names from submission to the end
(:class:`runner.trace.output.Claim`) and writes the files that come back under them, so workers need no
shared file system.

Lost workers: when the Ray worker process running a case dies (or its raylet, or its node) the case is
submitted once more (:data:`RETRIES`); the lost attempt left nothing here (files come back only with a
result), so the retry gives the same trace a first attempt would. Lost twice, the case is ``crashed``
(exit 3). A case whose *engine* kills its process is not retried: that happens inside the task, is
deterministic, and is reported as ``crashed (signal N)`` exactly as locally.

Interruptions (Ctrl-C, SIGTERM): the tasks in flight are cancelled (their Ray workers are killed) and
nothing more is submitted; every case that finished before keeps its trace here, the cancelled ones
bring nothing back.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from reports import trace_format as tf
from runner.errors import TraceError, UsageError
from runner.exec.cases import Case, CaseResult, case_result, named, run_case
from runner.exec.pool import CRASHED, RETURNED, Ending, Job, Pool
from runner.exec.transport import encode_error
from runner.trace.output import Claim, publish_trace, write_error

__all__ = ["RAY_HINT", "RETRIES", "RayExecutor", "ray_task"]

RAY_HINT = "pip install 'physics-scenarios[ray]'"
#: times a case whose Ray worker was lost is submitted again
RETRIES = 1


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
                     case.trace_process, case.budget, case.sha256, memory=case.memory)  # fmt: skip
        with Pool(1) as pool:  # the ceiling is the command's (case.memory), not the Ray worker's environment
            (ending,) = pool.run([Job(run_case, (local,), case.backend, case.budget, True, case.cost, case.memory)])
        written = {f.name: f.read_bytes() for f in sorted(out.iterdir()) if f.is_file()} if out.is_dir() else {}
    return {"ending": ending, "written": written}


class _Lost(Exception):
    """The Ray worker (or raylet, or node) running a case was lost."""


class RayExecutor:
    """Cases as Ray tasks (one CPU each) on the cluster at ``address`` ("auto", "host:port",
    "ray://host:10001"), or on a local instance started here (``address=None``; ``jobs`` CPUs, default
    all). At most ``jobs`` tasks are in flight when ``jobs`` is given. ``runtime_env`` is passed to
    ``ray.init`` (e.g. py_modules). ``retried`` lists the cases submitted again after a lost worker."""

    def __init__(self, address: str | None = None, jobs: int | None = None,
                 runtime_env: dict[str, Any] | None = None, *, force: bool = False) -> None:  # fmt: skip
        try:
            import ray
        except ImportError as exc:
            raise UsageError(f"`--executor ray` needs Ray (not installed); install it with: {RAY_HINT}") from exc
        self._ray = ray
        self.jobs = jobs
        self.force = force
        self.retried: list[int] = []
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
        # retries are ours (see the module docstring): Ray's own would hide them from the caller
        self._task = ray.remote(num_cpus=1, max_retries=0)(ray_task)

    def run(self, cases: Sequence[Case], on_result: Callable[[int, CaseResult], None] | None = None,
            on_progress: Callable[[int, int, int], None] | None = None,
            on_start: Callable[[int], None] | None = None) -> list[CaseResult]:  # fmt: skip
        ray = self._ray
        cases = [named(c) for c in cases]
        stack = list(reversed(sorted(range(len(cases)), key=lambda i: (-cases[i].cost, i))))
        limit = self.jobs or len(cases) or 1
        claims = _Claims(cases, self.force)
        flight: dict[Any, int] = {}
        done: dict[int, CaseResult] = {}
        attempts: dict[int, int] = {}

        def finish(index: int, ending: Ending) -> None:
            claims.release(index)  # the files are in place: the outcome file, if any, is written under a new claim
            done[index] = case_result(cases[index], ending)
            if on_result is not None:
                on_result(index, done[index])

        def submit(index: int) -> None:
            attempts[index] = attempts.get(index, 0) + 1
            flight[self._task.remote(cases[index].bundle())] = index

        try:
            while stack or flight:
                while stack and len(flight) < limit:
                    index = stack.pop()
                    refused = claims.take(index)
                    if refused is not None:
                        finish(index, refused)
                        continue
                    submit(index)
                    if on_start is not None:
                        on_start(index)
                if not flight:
                    continue
                ready, _ = ray.wait(list(flight), num_returns=1)
                for ref in ready:
                    index = flight.pop(ref)
                    try:
                        ending = self._collect(ref, cases[index])
                    except _Lost as exc:
                        if attempts[index] <= RETRIES:
                            self.retried.append(index)
                            submit(index)
                            continue
                        ending = Ending(CRASHED, None, output=f"the Ray worker running the case was lost: {exc}")
                    finish(index, ending)
        except BaseException:
            for ref in flight:
                ray.cancel(ref, force=True)
            raise
        finally:
            claims.release_all()
        return [done[i] for i in range(len(cases))]

    def _collect(self, ref: Any, case: Case) -> Ending:
        """The task's ending, its files put in place (this process holds the case's names); :class:`_Lost`
        if its worker was lost."""
        ray = self._ray
        try:
            reply: dict[str, Any] = ray.get(ref)
        except ray.exceptions.RayTaskError:  # ray_task reports every error of the case: this is a bug in it
            raise
        except ray.exceptions.RayError as exc:  # the Ray worker, its raylet or its node died: not the engine's doing
            raise _Lost(str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__) from exc
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
        raise write_error(exc, f"the trace folder {out}") from exc
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
