"""Running many cases (file x variant x backend x parameter set) elsewhere: local worker processes or Ray.

Every executor runs each case in a worker process through the one protocol of :mod:`runner.exec.pool`
and :mod:`runner.exec.cases`, and returns one :class:`~runner.exec.cases.CaseResult` per case, in the
order given, whatever order they finish in:

* :class:`LocalExecutor`: ``jobs`` worker processes (``jobs == 1``: the serial path, one worker reused
  from case to case); ``isolate`` gives every case a process of its own. A case whose engine kills its
  process is ``crashed (signal N)``, one over its budget ``timed out``; the other cases go on.
* :class:`RayExecutor` (extra ``ray``; :mod:`runner.exec.remote`): each case is a Ray task that runs the
  same local protocol inside the Ray worker, so a crash is still ``crashed (signal N)`` with its
  ``.partial`` trace, and a budget still holds. The scenario file and its sounds travel with the task and
  every file the run wrote comes back, so workers need no shared file system. A lost Ray worker's case is
  submitted once more.

Each case's output names are owned for the whole case (:class:`runner.trace.output.Claim`: taken by the
worker that writes them, or by this process for a Ray task, whose files it writes when they come back):
a concurrent run for the same names fails at once with exit 2 and never damages this one.

Results are deterministic: the same cases give the same results and byte-identical traces whichever
executor runs them (wall time stays out of them, in ``CaseResult.wall_seconds`` and the ``.cost.json``).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Protocol

from runner.errors import ExitCode, TraceError, UsageError
from runner.exec.cases import Case, CaseResult, case_result, estimate_cost, named, run_case
from runner.exec.exits import most_severe
from runner.exec.pool import TIMEOUT_GRACE, Ending, Job, Pool
from runner.exec.remote import RayExecutor
from runner.trace.output import foreign, refusal

__all__ = [
    "EXECUTORS",
    "Case",
    "CaseResult",
    "Executor",
    "LocalExecutor",
    "OnProgress",
    "OnResult",
    "OnStart",
    "RayExecutor",
    "add_arguments",
    "check_outputs",
    "estimate_cost",
    "make_executor",
    "status_code",
]

EXECUTORS = ("local", "ray")
OnResult = Callable[[int, CaseResult], None]
OnProgress = Callable[[int, int, int], None]  # (case index, steps done, steps in all)
OnStart = Callable[[int], None]  # (case index): the case was handed to a worker


class Executor(Protocol):
    """Runs cases and returns their results in the order given (see the module docstring)."""

    def run(self, cases: Sequence[Case], on_result: OnResult | None = None,
            on_progress: OnProgress | None = None,
            on_start: OnStart | None = None) -> list[CaseResult]: ...  # fmt: skip

    def close(self) -> None: ...


def check_outputs(cases: Iterable[Case], force: bool = False) -> None:
    """Refuse, before anything runs, to overwrite files under these cases' output names that this tool did
    not write (``--force`` allows it); the tool's own earlier outputs are replaced without asking."""
    if force:
        return
    left = foreign(Path(c.trace) for c in cases if c.trace is not None)
    if left:
        raise TraceError(refusal(left))


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
            on_progress: OnProgress | None = None, on_start: OnStart | None = None) -> list[CaseResult]:  # fmt: skip
        cases = [replace(named(c), force=c.force or self.force) for c in cases]
        results: dict[int, CaseResult] = {}

        def end(index: int, ending: Ending) -> None:
            results[index] = case_result(cases[index], ending)
            if on_result is not None:
                on_result(index, results[index])

        jobs = [Job(run_case, (c,), c.backend, c.budget, self.isolate, c.cost, c.memory) for c in cases]
        with Pool(min(self.jobs, max(1, len(cases))), timeout_grace=self.grace) as pool:
            pool.run(jobs, end, on_progress, None if on_start is None else lambda i: on_start(i))
        return [results[i] for i in range(len(cases))]

    def close(self) -> None:
        """Nothing stays running between run() calls."""


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
