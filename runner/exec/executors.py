"""Running many cases (file x variant x backend x parameter set) in parallel, locally or on a Ray cluster.

A :class:`Case` names a scenario file, a variant, ``--set`` overrides, a backend and an output folder.
:func:`run_case` runs one case in the current process; an executor runs many and returns one
:class:`CaseResult` per case, in the order given, whatever order they finish in:

* :class:`LocalExecutor` (the default): ``jobs == 1`` runs in this process; otherwise a pool of ``jobs``
  spawned worker processes, each running one case at a time. A worker that dies (an engine crash) makes
  its case ``crashed``; the other cases go on.
* :class:`RayExecutor` (extra ``ray``): submits each case as a Ray task to an existing cluster
  (``address``) or to a local instance it starts. The scenario file and its sounds travel with the task
  and every file the run writes (trace, cost) comes back, so workers need no shared file system.

Results are deterministic: the same cases give the same results and byte-identical traces whichever
executor runs them (wall time stays out of them, in ``CaseResult.wall_seconds`` and the ``.cost.json``).
"""

from __future__ import annotations

import math
import multiprocessing
import os
import signal
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any, Protocol

from backends.errors import PhysicsScenariosError
from runner.errors import ScenarioError, UsageError

__all__ = [
    "Case",
    "CaseResult",
    "Executor",
    "LocalExecutor",
    "RayExecutor",
    "estimate_cost",
    "make_executor",
    "run_case",
]

EXECUTORS = ("local", "ray")
RAY_HINT = "pip install 'physics-scenarios[ray]'"
Files = tuple[tuple[str, bytes], ...]  # (path relative to the scenario's folder, content)


@dataclass(frozen=True)
class Case:
    path: str  # the scenario file
    variant: str | None  # None: the base case
    backend: str
    overrides: tuple[tuple[str, Any], ...] = ()  # --set items, applied in order
    out_dir: str | None = None  # traces go here; None: no trace
    files: Files = ()  # the scenario's files, for workers that cannot read `path` (see bundle())
    cost: float = 0.0  # an estimate of the work (see estimate_cost): costly cases are started first
    record_every: int = 1  # the trace gets every k-th step (run_loaded's record_every)

    def bundle(self) -> Case:
        """This case carrying its scenario file and the sounds it names (for remote workers)."""
        from runner.language.load import load_scenario

        path = Path(self.path)
        loaded = load_scenario(path, self.variant, self.overrides)
        files = [(path.name, path.read_bytes())]
        files += [(str(rel), (path.parent / rel).read_bytes()) for rel in loaded.model.sounds.values()]
        return Case(self.path, self.variant, self.backend, self.overrides, self.out_dir, tuple(files), self.cost,
                    self.record_every)  # fmt: skip


def estimate_cost(loaded: Any) -> float:
    """Steps x bodies x substeps of a loaded case: the order to start cases in (longest first keeps the
    last worker from finishing alone)."""
    from runner.language.names import expand_bodies

    world = loaded.model.world
    return math.floor(world.duration / world.dt + 0.5) * (len(expand_bodies(loaded.model)) + 1) * world.substeps


def _schedule(cases: Sequence[Case]) -> list[tuple[int, Case]]:
    """(index, case) in the order to submit them, as a stack (pop() gives the next): costliest first."""
    order = sorted(enumerate(cases), key=lambda item: (-item[1].cost, item[0]))
    return list(reversed(order))


@dataclass
class CaseResult:
    case: Case
    status: str  # passed | failed | engine-failure | error | crashed | interrupted
    result: Any = None  # runner.sim.session.RunResult when the run completed (any status but the last three)
    failure: str | None = None
    error_type: str | None = None  # for "error": the exception class (UnsupportedFeature, ...)
    written: dict[str, bytes] = field(default_factory=dict)  # files a remote run wrote, by name
    wall_seconds: float = 0.0  # never in tables or traces

    @property
    def passed(self) -> bool:
        return self.status == "passed"

    def raise_error(self) -> None:
        """Raise again the exception that made this an ``error`` (for exit codes), else nothing."""
        if self.status != "error":
            return
        from runner import errors as e

        cls = getattr(e, self.error_type or "", None)
        if not (isinstance(cls, type) and issubclass(cls, PhysicsScenariosError)) or cls is e.ScenarioValidationError:
            cls = ScenarioError if self.error_type == "ScenarioValidationError" else PhysicsScenariosError
        raise cls(self.failure or "")


def run_case(case: Case) -> CaseResult:
    """Run one case here. Errors of the product come back as status ``error``; an interruption propagates."""
    from runner.language.load import load_scenario
    from runner.sim.run import run_loaded

    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="scenario-case-") as tmp:
        path = Path(case.path)
        if case.files:
            for rel, data in case.files:
                target = Path(tmp, "src", rel)
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(data)
            path = Path(tmp, "src", case.files[0][0])
        out_dir = None if case.out_dir is None else Path(case.out_dir)
        if out_dir is not None and case.files:
            out_dir = Path(tmp, "out")  # gathered back by the caller
        try:
            loaded = load_scenario(path, case.variant, case.overrides)
            result = run_loaded(loaded, case.backend, out_dir, record_every=case.record_every)
        except (PhysicsScenariosError, OSError) as exc:
            return CaseResult(case, "error", failure=str(exc), error_type=type(exc).__name__,
                              wall_seconds=time.perf_counter() - start)  # fmt: skip
        written = {}
        if out_dir is not None and case.files and case.out_dir is not None:
            written = {f.name: f.read_bytes() for f in sorted(out_dir.iterdir()) if f.is_file()}
            if result.trace:  # where the caller puts it
                result.trace = str(Path(case.out_dir, Path(result.trace).name))
    return CaseResult(case, result.status, result, result.failure, None, written, time.perf_counter() - start)


class Executor(Protocol):
    def run(self, cases: Sequence[Case], on_result: Callable[[int, CaseResult], None] | None = None
            ) -> list[CaseResult]: ...  # fmt: skip

    def close(self) -> None: ...


# --- local ------------------------------------------------------------------------------------------


class _WorkerStop(KeyboardInterrupt):
    """SIGTERM in a worker: finish the trace as interrupted, like Ctrl-C."""


_busy = False  # a worker is running a case


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    if _busy:
        raise _WorkerStop()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # idle (the pool is being torn down): just end
    os.kill(os.getpid(), signal.SIGTERM)


def _init_worker() -> None:
    signal.signal(signal.SIGTERM, _on_sigterm)


def _pool_task(case: Case) -> CaseResult:
    global _busy
    _busy = True
    try:
        return run_case(case)
    finally:
        _busy = False


class LocalExecutor:
    """A pool of ``jobs`` spawned processes (``jobs == 1``: this process)."""

    def __init__(self, jobs: int = 1) -> None:
        if jobs < 1:
            raise UsageError(f"Invalid `-j`. Expected a positive number of processes. Received: {jobs}")
        self.jobs = jobs

    def run(self, cases: Sequence[Case], on_result: Callable[[int, CaseResult], None] | None = None
            ) -> list[CaseResult]:  # fmt: skip
        done: dict[int, CaseResult] = {}

        def finish(i: int, r: CaseResult) -> None:
            done[i] = r
            if on_result is not None:
                on_result(i, r)

        if self.jobs == 1 or len(cases) <= 1:
            for i, case in enumerate(cases):
                finish(i, run_case(case))
        else:
            self._pool(_schedule(cases), min(self.jobs, len(cases)), finish)
        return [done[i] for i in range(len(cases))]

    def _pool(self, todo: list[tuple[int, Case]], jobs: int, finish: Callable[[int, CaseResult], None]) -> None:
        """At most ``jobs`` cases in flight; if a worker dies, each case then in flight is run alone to
        find the one that crashes (it is reported ``crashed``) and the pool is started again."""
        while todo:
            pool = ProcessPoolExecutor(jobs, mp_context=_context(), initializer=_init_worker)
            flight: dict[Future[CaseResult], tuple[int, Case]] = {}
            suspects: list[tuple[int, Case]] = []
            try:
                while todo or flight:
                    while todo and len(flight) < jobs:
                        item = todo.pop()
                        flight[pool.submit(_pool_task, item[1])] = item
                    ready, _ = wait(flight, return_when=FIRST_COMPLETED)
                    for future in ready:
                        item = flight.pop(future)
                        try:
                            finish(item[0], future.result())
                        except BrokenProcessPool:
                            suspects.append(item)
                    if suspects:
                        suspects += list(flight.values())
                        break
            except BaseException:
                _stop(pool)
                raise
            finally:
                pool.shutdown(wait=True, cancel_futures=True)
            for index, case in sorted(suspects):
                finish(index, self._alone(case))

    @staticmethod
    def _alone(case: Case) -> CaseResult:
        with ProcessPoolExecutor(1, mp_context=_context(), initializer=_init_worker) as p:
            try:
                return p.submit(_pool_task, case).result()
            except BrokenProcessPool:
                return CaseResult(case, "crashed", failure=f"the worker running {Path(case.path).name} on "
                                  f"{case.backend} died (the engine crashed?)")  # fmt: skip

    def close(self) -> None:
        """Nothing stays running between run() calls."""


def _context() -> Any:
    """How workers start. On Linux: ``fork`` when this process is safe to copy (one thread, no engine
    imported: the CLI's case), which costs nothing; else ``forkserver`` (workers fork from a server that
    imported the runner once, about 0.7 s); elsewhere ``spawn`` (each worker imports everything, ~1.5 s)."""
    import sys
    import threading

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


_PRELOAD = ["numpy", "runner.sim.run", "runner.trace.writer", "runner.exec.executors", "reports.trace_reader"]


def _stop(pool: ProcessPoolExecutor, grace: float = 5.0) -> None:
    """Interrupted: SIGTERM every worker (each finishes its trace as interrupted), then wait for them."""
    processes = list(getattr(pool, "_processes", {}).values())  # no public handle on the workers
    for p in processes:
        if p.is_alive():
            p.terminate()
    deadline = time.monotonic() + grace
    for p in processes:
        p.join(max(0.0, deadline - time.monotonic()))
        if p.is_alive():
            p.kill()


# --- Ray ----------------------------------------------------------------------------------------------


class RayExecutor:
    """Cases as Ray tasks (one CPU each) on the cluster at ``address`` ("auto", "ray://host:10001"), or on
    a local instance started here (``address=None``; ``jobs`` CPUs, default all). At most ``jobs`` tasks
    are in flight when ``jobs`` is given. ``runtime_env`` is passed to ``ray.init`` (e.g. py_modules)."""

    def __init__(self, address: str | None = None, jobs: int | None = None,
                 runtime_env: dict[str, Any] | None = None) -> None:  # fmt: skip
        try:
            import ray
        except ImportError as exc:
            raise UsageError(f"`--executor ray` needs Ray (not installed); install it with: {RAY_HINT}") from exc
        self._ray = ray
        self.jobs = jobs
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
        self._task = ray.remote(num_cpus=1, max_retries=0)(run_case)

    def run(self, cases: Sequence[Case], on_result: Callable[[int, CaseResult], None] | None = None
            ) -> list[CaseResult]:  # fmt: skip
        ray = self._ray
        todo = _schedule(cases)
        limit = self.jobs or len(cases) or 1
        flight: dict[Any, tuple[int, Case]] = {}
        done: dict[int, CaseResult] = {}
        try:
            while todo or flight:
                while todo and len(flight) < limit:
                    index, case = todo.pop()
                    flight[self._task.remote(case.bundle())] = (index, case)
                ready, _ = ray.wait(list(flight), num_returns=1)
                for ref in ready:
                    index, case = flight.pop(ref)
                    done[index] = self._collect(ref, case)
                    if on_result is not None:
                        on_result(index, done[index])
        except BaseException:
            for ref in flight:
                ray.cancel(ref, force=True)
            raise
        return [done[i] for i in range(len(cases))]

    def _collect(self, ref: Any, case: Case) -> CaseResult:
        ray = self._ray
        try:
            result: CaseResult = ray.get(ref)
        except (ray.exceptions.WorkerCrashedError, ray.exceptions.NodeDiedError) as exc:
            return CaseResult(case, "crashed", failure=f"the Ray worker died: {exc}")
        except ray.exceptions.RayTaskError as exc:
            return CaseResult(case, "error", failure=str(exc.cause), error_type=type(exc.cause).__name__)
        result.case = case
        if case.out_dir is not None:
            out = Path(case.out_dir)
            out.mkdir(parents=True, exist_ok=True)
            for name, data in result.written.items():
                (out / name).write_bytes(data)
            result.written = {}
        return result

    def close(self) -> None:
        if self._started and self._ray.is_initialized():
            self._ray.shutdown()


def make_executor(kind: str = "local", jobs: int = 1, ray_address: str | None = None) -> Executor:
    """The executor a command asked for (``--executor``, ``-j``, ``--ray-address``)."""
    if kind == "local":
        if ray_address:
            raise UsageError("`--ray-address` needs `--executor ray`")
        return LocalExecutor(jobs)
    if kind == "ray":
        return RayExecutor(ray_address, jobs if jobs > 1 else None)
    raise UsageError(f"Invalid `--executor`. Expected one of {', '.join(EXECUTORS)}. Received: {kind}")


def add_arguments(parser: Any, jobs_default: int = 1) -> None:
    """``-j``, ``--executor`` and ``--ray-address``, for the commands that run many cases."""
    parser.add_argument("-j", "--jobs", type=int, default=jobs_default, metavar="N",
                        help=f"cases run in parallel (default {jobs_default})")  # fmt: skip
    parser.add_argument("--executor", choices=EXECUTORS, default="local",
                        help="local process pool (default) or a Ray cluster (extra `ray`)")  # fmt: skip
    parser.add_argument("--ray-address", metavar="ADDR",
                        help="a Ray cluster (`auto`, `ray://host:10001`); default: start a local one")  # fmt: skip


def status_code(results: Sequence[CaseResult]) -> int:
    """The exit code for a batch: 3 when any case met an engine failure or crashed, 1 when any failed."""
    from runner.errors import ExitCode

    if any(r.status in ("engine-failure", "crashed") for r in results):
        return ExitCode.ENGINE_FAILURE
    return ExitCode.OK if all(r.passed for r in results) else ExitCode.ASSERTION_FAILED
