"""The parent side of the protocol: worker processes, time limits, signals, and how each job ended.

A :class:`Pool` runs :class:`Job` s on up to ``workers`` worker processes (:func:`runner.exec.child.serve`),
costliest first, each job on a worker that ran only jobs of the same ``affinity`` (one engine per
process: DART and ODE both carry an ODE library). Workers are reused unless a job asks for a ``fresh``
one (``--isolate``), crashed, or was stopped. Everything runs in the calling thread: the pool waits on
the workers' pipes and process sentinels at once.

How a job ended is an :class:`Ending`: ``returned`` (the job's payload), ``crashed`` (its process was
killed by a signal it did not get from us: a segfault, an abort, the OOM killer), ``exited`` (the process
ended without a result), ``timed-out`` (over its ``timeout``: the worker gets SIGTERM, finishes its trace
at the next step and returns, or gets SIGKILL ``TIMEOUT_GRACE`` seconds later), ``over-memory`` (its
resident memory went over its ``memory`` ceiling, read every ``POLL_SECONDS`` (runner.exec.memory): it
gets SIGKILL at once, since memory that grows cannot wait for a grace period; its trace is kept as
``.partial`` up to its last chunk) or ``interrupted`` (the caller was interrupted). ``output`` is what
the worker printed during the job (engines print there; an abort's message is in it).

Interruptions: when the caller gets SIGINT or SIGTERM (raised as KeyboardInterrupt by
:mod:`runner.interrupts`) the pool sends the same signal to each busy worker, waits up to
``STOP_GRACE`` seconds for them to finish their traces, kills what is left, and re-raises. A second
signal meanwhile kills every worker at once (SIGKILL: even one inside a long engine call that ignores
signals), leaving its trace as a ``.partial`` file.

Workers start by ``fork`` when this process is safe to copy (Linux, one thread, no engine imported: the
CLI's case; nothing to import again), else from a ``forkserver`` that imported the runner once, else
``spawn`` (see :func:`context`).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import wait
from pathlib import Path
from typing import Any

from runner import interrupts
from runner.exec import memory as mem
from runner.exec.child import serve

__all__ = [
    "CRASHED",
    "EXITED",
    "INTERRUPTED",
    "OVER_MEMORY",
    "RETURNED",
    "STOP_GRACE",
    "TIMED_OUT",
    "TIMEOUT_GRACE",
    "Ending",
    "Job",
    "Pool",
    "context",
]

RETURNED, CRASHED, EXITED, TIMED_OUT, INTERRUPTED = "returned", "crashed", "exited", "timed-out", "interrupted"
OVER_MEMORY = "over-memory"
#: seconds a worker has to finish its trace after its time limit's SIGTERM, before SIGKILL
TIMEOUT_GRACE = 5.0
#: seconds busy workers have to finish their traces after the caller is interrupted, before SIGKILL
STOP_GRACE = 10.0
OUTPUT_LIMIT = 64_000  # characters of a job's output kept
_PRELOAD = ["numpy", "runner.exec.cases", "runner.sim.run", "runner.trace.writer", "reports.trace_reader"]


@dataclass(frozen=True)
class Job:
    """``function(*args, report)`` in a worker; it returns a JSON-able payload."""

    function: Callable[..., dict[str, Any]]
    args: tuple[Any, ...]
    affinity: str = ""  # jobs of different affinities never share a process
    timeout: float | None = None  # wall-clock seconds from the job's start
    fresh: bool = False  # a process that ran nothing before and runs nothing after
    cost: float = 0.0  # costlier jobs start first
    memory: int | None = None  # the worker's memory ceiling (bytes; 0: none); None: SCENARIO_MEMORY_LIMIT's


@dataclass(frozen=True)
class Ending:
    """How a worker's job ended: returned (with its payload), crashed, exited, timed out or interrupted."""

    how: str  # RETURNED, CRASHED, EXITED, TIMED_OUT or INTERRUPTED
    payload: dict[str, Any] | None = None  # what the job returned, if it did
    signal: int | None = None  # the signal that ended the process, if one did
    returncode: int | None = None
    output: str = ""
    timeout: float | None = None
    wall_seconds: float = 0.0
    memory: int | None = None  # the ceiling the job ran under (bytes), when it had one
    peak: int | None = None  # the most resident memory read from the worker during the job (bytes)
    progress: tuple[int, int] | None = None  # the last (steps done, steps in all) the job reported


def context() -> Any:
    """How workers start (see the module docstring)."""
    from backends.registry import engine_modules

    methods = multiprocessing.get_all_start_methods()
    engines = engine_modules() & set(sys.modules)
    if sys.platform.startswith("linux") and "fork" in methods and threading.active_count() == 1 and not engines:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(_PRELOAD)
        return ctx
    return multiprocessing.get_context("spawn")


def schedule(jobs: Sequence[Job]) -> list[int]:
    """Job indices as a stack (pop() gives the next): costliest first, ties in the order given."""
    order = sorted(range(len(jobs)), key=lambda i: (-jobs[i].cost, i))
    return list(reversed(order))


@dataclass(eq=False)
class _Worker:
    """A worker process of the pool, its pipe and log, and how many jobs it has run."""

    process: Any
    conn: Any
    log: Path
    affinity: str | None = None
    jobs_run: int = 0
    index: int | None = None  # the job in flight
    started: float = 0.0
    deadline: float | None = None
    kill_at: float | None = None
    stopping: str | None = None  # TIMED_OUT or INTERRUPTED: we signalled it
    offset: int = 0  # where the current job's output starts in the log
    reusable: bool = True
    memory: int | None = None  # the current job's ceiling
    peak: int = 0
    progress: tuple[int, int] | None = None
    messages: list[tuple[Any, ...]] = field(default_factory=list)

    def output(self) -> str:
        try:
            with open(self.log, "rb") as f:
                f.seek(self.offset)
                data = f.read()
        except OSError:
            return ""
        self.offset += len(data)
        return data.decode("utf-8", errors="replace")[-OUTPUT_LIMIT:]

    def signal(self, sig: int) -> None:
        try:
            os.kill(self.process.pid, sig)
        except (ProcessLookupError, TypeError):
            pass


class Pool:
    """Runs jobs on worker processes (see the module docstring). ``close()`` ends every worker."""

    def __init__(self, workers: int = 1, *, timeout_grace: float = TIMEOUT_GRACE, stop_grace: float = STOP_GRACE):
        if workers < 1:
            raise ValueError(f"Invalid `workers`. Expected an integer >= 1. Received: {workers!r}")
        self.size = workers
        self.timeout_grace = timeout_grace
        self.stop_grace = stop_grace
        self._ctx: Any = None
        self._workers: list[_Worker] = []
        self._folder = tempfile.TemporaryDirectory(prefix="scenario-workers-")
        self._started = 0
        self.started: Counter[str] = Counter()  # worker processes started, by the affinity of their first job
        self.memory = mem.ceiling()  # for jobs that name none

    # ---- workers ---------------------------------------------------------------------------------

    def _start(self) -> _Worker:
        if self._ctx is None:
            self._ctx = context()
        self._started += 1
        log = Path(self._folder.name) / f"worker{self._started}.log"
        parent, child = self._ctx.Pipe()
        process = self._ctx.Process(target=serve, args=(child, str(log)), name=f"scenario-worker-{self._started}")
        worker = _Worker(process, parent, log)
        self._workers.append(worker)  # before it starts: an interruption during start() leaves nothing untracked
        try:
            process.start()
        finally:
            child.close()
        return worker

    def _retire(self, worker: _Worker) -> None:
        self._workers.remove(worker)
        if worker.process.pid is None:  # never started
            worker.conn.close()
            return
        try:
            worker.conn.send(None)
        except (OSError, ValueError):
            pass
        worker.process.join(2.0)
        if worker.process.is_alive():
            worker.process.kill()
            worker.process.join()
        worker.conn.close()

    def close(self) -> None:
        for worker in list(self._workers):
            if worker.index is not None and worker.process.pid is not None:
                worker.process.kill()
            self._retire(worker)
        self._folder.cleanup()

    def __enter__(self) -> Pool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _worker_for(self, job: Job) -> _Worker | None:
        idle = [w for w in self._workers if w.index is None]
        if not job.fresh:
            for w in idle:
                if w.reusable and w.affinity == job.affinity:
                    return w
        for w in idle:
            if w.jobs_run == 0 and w.affinity is None:
                return w
        if len(self._workers) >= self.size:
            if not idle:
                return None
            self._retire(idle[0])
        self.started[job.affinity] += 1
        return self._start()

    # ---- running ---------------------------------------------------------------------------------

    def run(
        self,
        jobs: Sequence[Job],
        on_end: Callable[[int, Ending], None] | None = None,
        on_progress: Callable[[int, int, int], None] | None = None,
        before: Callable[[int], Ending | None] | None = None,
    ) -> list[Ending]:
        """Run every job; endings in the order of ``jobs``. ``before(i)`` is called as job ``i`` starts and
        may return an ending instead (the job is then not run); ``on_end(i, ending)`` as each ends."""
        todo = schedule(jobs)
        endings: dict[int, Ending] = {}

        def end(index: int, ending: Ending) -> None:
            endings[index] = ending
            if on_end is not None:
                on_end(index, ending)

        try:
            while todo or self._busy():
                while todo:
                    index = todo[-1]
                    worker = self._worker_for(jobs[index])
                    if worker is None:
                        break
                    todo.pop()
                    skipped = before(index) if before is not None else None
                    if skipped is not None:
                        end(index, skipped)
                        continue
                    self._dispatch(worker, index, jobs[index])
                self._step(jobs, end, on_progress)
        except BaseException as exc:
            self._stop(exc, jobs, end, on_progress)
            raise
        return [endings[i] for i in range(len(jobs))]

    def _busy(self) -> list[_Worker]:
        return [w for w in self._workers if w.index is not None]

    def _dispatch(self, worker: _Worker, index: int, job: Job) -> None:
        now = time.monotonic()
        worker.index, worker.started, worker.stopping, worker.kill_at = index, now, None, None
        worker.deadline = None if job.timeout is None else now + job.timeout
        worker.memory = self.memory if job.memory is None else job.memory or None
        worker.peak, worker.progress = 0, None
        worker.affinity = job.affinity
        worker.jobs_run += 1
        worker.reusable = not job.fresh
        worker.output()  # skip what came before this job
        try:
            worker.conn.send((index, job.function, job.args))
        except OSError:  # the worker died as it started: _poll finds it dead and says how
            pass

    def _step(self, jobs: Sequence[Job], end: Callable[[int, Ending], None],
              on_progress: Callable[[int, int, int], None] | None) -> None:  # fmt: skip
        """Wait for something to happen (a message, a death, a deadline), then deal with it."""
        busy = self._busy()
        if not busy:
            return
        now = time.monotonic()
        marks = [t for w in busy for t in (w.deadline if w.stopping is None else None, w.kill_at) if t is not None]
        watched = any(w.memory is not None and w.stopping is None for w in busy)
        timeout = max(0.0, min([1.0, *(t - now for t in marks), *([mem.POLL_SECONDS] if watched else [])]))
        wait([x for w in busy for x in (w.conn, w.process.sentinel)], timeout)
        now = time.monotonic()
        for worker in busy:
            self._watch_memory(worker)
            ending = self._poll(worker, jobs[worker.index or 0], on_progress)
            if ending is not None:
                index = worker.index
                worker.index = None
                if ending.how != RETURNED or worker.stopping is not None or not worker.process.is_alive():
                    worker.reusable = False
                if not worker.reusable:
                    self._retire(worker)
                end(int(index or 0), ending)
                continue
            if worker.stopping is None and worker.deadline is not None and now >= worker.deadline:
                worker.stopping, worker.kill_at = TIMED_OUT, now + self.timeout_grace
                worker.signal(signal.SIGTERM)
            elif worker.kill_at is not None and now >= worker.kill_at:
                worker.signal(signal.SIGKILL)
                worker.kill_at = None

    @staticmethod
    def _watch_memory(worker: _Worker) -> None:
        """Kill a worker over its memory ceiling (SIGKILL at once: see the module docstring)."""
        if worker.memory is None or worker.stopping is not None or worker.process.pid is None:
            return
        held = mem.resident(worker.process.pid)
        if held is None:
            return
        worker.peak = max(worker.peak, held)
        if held > worker.memory:
            worker.stopping, worker.kill_at = OVER_MEMORY, None
            worker.signal(signal.SIGKILL)

    def _poll(self, worker: _Worker, job: Job, on_progress: Callable[[int, int, int], None] | None) -> Ending | None:
        """Read the worker's messages; its job's ending if it has one."""
        dead = False
        try:
            while worker.conn.poll():
                message = worker.conn.recv()
                if message[0] == "progress":
                    worker.progress = (message[2], message[3])
                    if on_progress is not None:
                        on_progress(message[1], message[2], message[3])
                elif message[0] == "done":
                    return self._ending(worker, job, message[2])
        except (EOFError, OSError):
            dead = True
        if dead or not worker.process.is_alive():
            worker.process.join()
            return self._ending(worker, job, None)
        return None

    def _ending(self, worker: _Worker, job: Job, payload: dict[str, Any] | None) -> Ending:
        wall = time.monotonic() - worker.started
        output = worker.output()
        if payload is not None:
            how = RETURNED
            if worker.stopping is not None and payload.get("status") == "interrupted":
                how = worker.stopping
            return Ending(how, payload, output=output, timeout=job.timeout, wall_seconds=wall, memory=worker.memory,
                          peak=worker.peak or None, progress=worker.progress)  # fmt: skip
        code = worker.process.exitcode
        sig = -code if code is not None and code < 0 else None
        how = worker.stopping or (CRASHED if sig is not None else EXITED)
        return Ending(how, None, sig, code, output, job.timeout, wall, worker.memory, worker.peak or None,
                      worker.progress)  # fmt: skip

    def _stop(self, exc: BaseException, jobs: Sequence[Job], end: Callable[[int, Ending], None],
              on_progress: Callable[[int, int, int], None] | None) -> None:  # fmt: skip
        """The caller was interrupted: let busy workers finish their traces, then end every worker."""
        sig = interrupts.signal_of(exc) if isinstance(exc, KeyboardInterrupt) else int(signal.SIGTERM)
        for worker in self._busy():
            worker.stopping, worker.kill_at = INTERRUPTED, None
            worker.signal(sig)
        deadline = time.monotonic() + self.stop_grace
        try:
            while self._busy() and time.monotonic() < deadline:
                for worker in self._busy():
                    worker.deadline, worker.kill_at = None, deadline
                self._step(jobs, end, on_progress)
        except BaseException:  # a second signal: now
            for worker in self._busy():
                worker.signal(signal.SIGKILL)
            raise
        finally:
            for worker in list(self._workers):
                if worker.index is not None:
                    worker.signal(signal.SIGKILL)
                    worker.process.join()
                    index, worker.index = worker.index, None
                    end(index, self._ending(worker, jobs[index], None))
                self._retire(worker)
