"""Running the suite: every case on every backend in worker processes, through runner.exec's protocol.

Each (case, backend) is a job of :class:`runner.exec.pool.Pool` run by :func:`runner.conformance.worker.job`;
a backend's cases share worker processes (never with another backend: one engine per process). When a
worker dies (a segfault in an engine, a kill) or a case runs past the timeout, that case is marked
``crashed (signal N)``, ``crashed (exit N)`` or ``timed out after T s`` (the same words as `scenario run`)
and a fresh worker carries on with the next cases: one broken case never hides the others, and one
broken backend never hides the other backends.
"""

from __future__ import annotations

import os
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from backends.registry import engine_version
from runner.conformance.cases import Case
from runner.conformance.worker import job
from runner.exec.memory import ENV, MIB
from runner.exec.pool import CRASHED, EXITED, OVER_MEMORY, RETURNED, TIMED_OUT, Ending, Job, Pool

__all__ = ["BackendRun", "run_backend", "run_suite"]

LOG_TAIL = 2000  # characters of a crashed worker's output kept for the message


@dataclass
class BackendRun:
    """Everything one backend's workers reported."""

    backend: str
    engine_version: str
    results: dict[str, dict[str, Any]] = field(default_factory=dict)  # case id -> worker result
    wall_seconds: float = 0.0
    workers: int = 0  # processes started (1 unless a case crashed or timed out)


def _failure(status: str, message: str) -> dict[str, Any]:
    return {"status": status, "message": message, "checks": [], "wall_seconds": 0.0}


def _result(ending: Ending) -> dict[str, Any]:
    """The worker's result for a case, or what its death says."""
    tail = ending.output.strip()[-LOG_TAIL:]
    if ending.how == RETURNED and ending.payload is not None and "checks" in ending.payload:
        return ending.payload
    if ending.how == TIMED_OUT:
        return _failure(f"timed out after {ending.timeout:g} s", tail)
    if ending.how == OVER_MEMORY:
        return _failure(f"over its memory ceiling of {(ending.memory or 0) // MIB} MiB ({ENV})", tail)
    if ending.how == CRASHED:
        return _failure(f"crashed (signal {ending.signal})", tail)
    if ending.how == EXITED:
        return _failure(f"crashed (exit {ending.returncode})", tail)
    payload = ending.payload or {}
    error = payload.get("error") or {}
    return _failure("error", f"{error.get('qualname', payload.get('status', 'stopped'))}: {error.get('message', '')}")


def run_suite(
    cases: Sequence[Case],
    backends: Sequence[str],
    jobs: int | None = None,
    timeout: float = 120.0,
    on_done: Callable[[BackendRun], None] | None = None,
) -> dict[str, BackendRun]:
    """Run every case on every backend, ``jobs`` processes at a time (default: one per core)."""
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(backends) * max(1, len(cases)) or 1))
    work = [(b, c) for b in backends for c in cases]
    runs = {b: BackendRun(b, engine_version(b)) for b in backends}
    left = Counter(b for b, _ in work)
    first: dict[str, float] = {}
    start = time.monotonic()

    def before(index: int) -> Ending | None:
        first.setdefault(work[index][0], time.monotonic())
        return None

    def end(index: int, ending: Ending) -> None:
        backend, case = work[index]
        runs[backend].results[case.id] = _result(ending)
        left[backend] -= 1
        if left[backend] == 0:
            runs[backend].wall_seconds = time.monotonic() - first.get(backend, start)
            if on_done is not None:
                on_done(runs[backend])

    todo = [Job(job, (str(c.path), c.variant, b), b, timeout) for b, c in work]
    with Pool(jobs) as pool:
        pool.run(todo, end, None, before)
        for backend, count in pool.started.items():
            runs[backend].workers = count
    return runs


def run_backend(backend: str, cases: Sequence[Case], timeout: float) -> BackendRun:
    """Run ``cases`` on ``backend`` alone; every case gets a result."""
    return run_suite(cases, [backend], 1, timeout)[backend]
