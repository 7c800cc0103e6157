"""Batched sweeps (`scenario sweep --batch`, docs/batch.md): the cases of one backend as the worlds of one batch.

:class:`BatchedExecutor` groups the cases by backend (scenario file, variant) and runs each group as one job in
one worker process (:func:`run_batch_job`: :func:`runner.sim.lockstep.run_batch`), through the same pool
as every case (runner.exec.pool): its memory ceiling is the worker's, its time limit the longest budget of
its cases (in a batch each variant's budget counts from the batch's start), an interruption finishes every
variant's trace. A group the backend cannot batch (it has no batch, the worlds differ in what its batch
holds per world, or a case cannot even be set up) runs through the ordinary executor, case by case, and
``on_fallback(cases, reason)`` says why (``cases``: the group's, e.g. "the 256 cases on pybullet"). Either
way each case gets the :class:`~runner.exec.cases.CaseResult` a separate run would give: a batch's variant is
the same variant run alone on the same backend.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from backends.errors import PhysicsScenariosError
from runner import interrupts
from runner.errors import ScenarioError
from runner.exec.cases import Case, CaseResult, case_result, named
from runner.exec.executors import Executor, OnProgress, OnResult, OnStart
from runner.exec.pool import RETURNED, TIMEOUT_GRACE, Ending, Job, Pool
from runner.exec.transport import encode_error, result_to_json

__all__ = ["BatchedExecutor", "OnFallback", "run_batch_job"]

OnFallback = Callable[[str, str], None]  # (which cases, in words; why they run separately)
REFUSED, BATCHED = "refused", "batched"


class _Refused(Exception):
    """The group cannot run as one batch (the reason is the message)."""


def run_batch_job(cases: tuple[Case, ...], report: Any = None) -> dict[str, Any]:
    """The job (in a worker): run ``cases`` (one backend) as one batch. Its payload: ``refused`` with the
    reason, or ``batched`` with one :func:`runner.exec.cases.run_case`-like payload per case, or one payload
    (``interrupted``, ``error``) that stands for every case."""
    from runner.sim.lockstep import NotBatched, run_batch

    start = time.perf_counter()
    with interrupts.deferred(check_at_exit=False):
        try:
            loads = [_load(case, k) for k, case in enumerate(cases)]
            interrupts.check()
            out_dirs = [None if c.out_dir is None else Path(c.out_dir) for c in cases]
            results = run_batch(loads, cases[0].backend, out_dirs, report, [c.budget for c in cases],
                                cases[0].force, cases[0].record_every)  # fmt: skip
        except (_Refused, NotBatched) as exc:
            return {"status": REFUSED, "reason": str(exc), "wall_seconds": time.perf_counter() - start}
        except KeyboardInterrupt as exc:
            return {"status": "interrupted", "signal": interrupts.signal_of(exc),
                    "wall_seconds": time.perf_counter() - start}  # fmt: skip
        except Exception as exc:  # noqa: BLE001 - every error crosses to the parent with its class
            wrapped = interrupts.behind(exc)
            if wrapped is not None:
                return {"status": "interrupted", "signal": interrupts.signal_of(wrapped),
                        "wall_seconds": time.perf_counter() - start}  # fmt: skip
            return {"status": "error", "error": encode_error(exc), "wall_seconds": time.perf_counter() - start}
    wall = time.perf_counter() - start
    return {"status": BATCHED, "wall_seconds": wall,
            "payloads": [{"status": "completed", "result": result_to_json(r), "wall_seconds": r.wall_seconds}
                         for r in results]}  # fmt: skip


def _load(case: Case, k: int) -> Any:
    from runner.language.load import load_scenario

    try:
        loaded = case.loaded if case.loaded is not None else load_scenario(Path(case.path), case.variant,
                                                                            case.overrides)  # fmt: skip
        if case.sha256 is not None and loaded.sha256 != case.sha256:
            raise ScenarioError(f"{case.path} changed after it was loaded; run again")
    except PhysicsScenariosError as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise _Refused(f"variant {k} cannot be loaded ({first})") from exc
    return loaded


def _described(case: Case, count: int) -> str:
    variant = f" (variant {case.variant})" if case.variant is not None else ""
    return f"the {count} cases on {case.backend}{variant}" if count != 1 else f"the case on {case.backend}{variant}"


def groups(cases: Sequence[Case]) -> list[list[int]]:
    """Case indices by (backend, scenario file, variant, trace sampling), in the order first seen: a variant may
    add bodies, so each variant's parameter grid is a batch of its own."""
    found: dict[tuple[str, str, str | None, int], list[int]] = {}
    for i, case in enumerate(cases):
        found.setdefault((case.backend, case.path, case.variant, case.record_every), []).append(i)
    return list(found.values())


class BatchedExecutor:
    """Runs each backend's cases as one batch where they batch, else through ``separate`` (module docstring).
    ``jobs``: batches run at once (of different backends). ``on_progress`` gets a batch's steps (done, of its
    longest variant's) under the index of its first case; cases run separately report none."""

    def __init__(self, separate: Executor, jobs: int = 1, *, force: bool = False, grace: float = TIMEOUT_GRACE,
                 on_fallback: OnFallback | None = None) -> None:  # fmt: skip
        self.separate = separate
        self.jobs = max(1, jobs)
        self.force = force
        self.grace = grace
        self.on_fallback = on_fallback

    def run(self, cases: Sequence[Case], on_result: OnResult | None = None, on_progress: OnProgress | None = None,
            on_start: OnStart | None = None) -> list[CaseResult]:  # fmt: skip
        cases = [replace(named(c), force=c.force or self.force) for c in cases]
        batches = groups(cases)
        results: dict[int, CaseResult] = {}
        alone: list[int] = []

        def settle(i: int, res: CaseResult) -> None:
            results[i] = res
            if on_result is not None:
                on_result(i, res)

        def end(j: int, ending: Ending) -> None:
            members = batches[j]
            payload = ending.payload or {}
            if ending.how == RETURNED and payload.get("status") == REFUSED:
                alone.extend(members)
                if self.on_fallback is not None:
                    self.on_fallback(_described(cases[members[0]], len(members)), str(payload.get("reason", "")))
                return
            own = payload.get("payloads") if ending.how == RETURNED and payload.get("status") == BATCHED else None
            for k, i in enumerate(members):
                each = ending if own is None else replace(ending, payload=own[k])
                settle(i, case_result(cases[i], each))

        def started(j: int) -> None:
            if on_start is not None:
                for i in batches[j]:
                    on_start(i)

        def progress(j: int, k: int, n: int) -> None:
            if on_progress is not None:
                on_progress(batches[j][0], k, n)

        jobs = [self._job(tuple(cases[i] for i in members)) for members in batches]
        with Pool(min(self.jobs, max(1, len(jobs))), timeout_grace=self.grace) as pool:
            pool.run(jobs, end, progress, lambda j: started(j))
        if alone:
            alone.sort()
            self.separate.run([cases[i] for i in alone], lambda k, r: settle(alone[k], r), None,
                              None if on_start is None else lambda k: on_start(alone[k]))  # fmt: skip
        return [results[i] for i in range(len(cases))]

    @staticmethod
    def _job(members: tuple[Case, ...]) -> Job:
        budgets = [c.budget for c in members if c.budget is not None]
        return Job(run_batch_job, (members,), members[0].backend, max(budgets) if budgets else None, False,
                   sum(c.cost for c in members), members[0].memory)  # fmt: skip

    def close(self) -> None:
        self.separate.close()
