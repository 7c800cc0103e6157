"""Many variants of one scenario as the worlds of one batched engine (backends.batch, docs/batch.md).

Each variant has its own :class:`~runner.sim.session.Session` (its events, drives, assertions, trace) on its
own view of the batch. The sessions run in lockstep: each goes up to the moment before its engine step
(``Session.advance(pause=True)`` yields :data:`~runner.sim.session.BEFORE_STEP`, its inputs set), then one
``step_all`` advances every active world, then each session goes on (its view's ``step()`` returns at once,
or raises its world's failure) and reads its world. A session that ends (an ``end`` action, its last step,
an engine failure, the runner's blow-up check, its budget) drops out of the batch; the others go on.

A variant's budget counts from the batch's start: in a batch every world takes the wall time of all.
"""

from __future__ import annotations

import contextlib
import time as wallclock
from collections.abc import Callable, Generator, Sequence
from pathlib import Path

from backends.base import Backend
from backends.batch import WorldBatch
from backends.errors import EngineFailure, PhysicsScenariosError
from backends.registry import check_capabilities, get_backend
from runner import interrupts
from runner.compile.program import Program, build_program
from runner.language.load import LoadedScenario
from runner.sim.budget import Watchdog
from runner.sim.run import failure_result, finish_trace, open_trace, start_trace, trace_path
from runner.sim.session import BEFORE_STEP, RunResult, Session
from runner.trace.output import Claim, write_error

__all__ = ["NotBatched", "batch_refusal", "run_batch"]

Steps = Generator[float | str, None, RunResult]


def batch_refusal(cls: type[Backend], programs: Sequence[Program]) -> str | None:
    """Why these variants cannot run as one batch on ``cls`` (in words a user reads), or None."""
    batch = cls.world_batch()
    if batch is None or batch.backend.name != cls.name:  # another backend's batch (an inherited one): not this
        return f"backend {cls.name} does not batch worlds"
    return batch.why_not([p.world for p in programs])


class NotBatched(Exception):  # noqa: N818 - a decision, not an error: the variants run one by one instead
    """These variants cannot run as one batch; the message says why (:func:`batch_refusal`, or a variant that
    cannot be set up at all: alone, it reports that in its own words)."""


def prepare(loads: Sequence[LoadedScenario], backend_name: str) -> tuple[type[WorldBatch], list[Program]]:
    """The batch class and the variants' programs, or :class:`NotBatched`."""
    programs: list[Program] = []
    which = "the backend"
    try:
        cls = get_backend(backend_name)
        interrupts.check()  # a signal during the engine's import is an interruption
        for k, loaded in enumerate(loads):
            which = f"variant {k}"
            programs.append(build_program(loaded))
            check_capabilities(cls, programs[-1].world)
    except PhysicsScenariosError as exc:
        first = str(exc).splitlines()[0].split(". ")[0].rstrip(".")
        raise NotBatched(f"{which} cannot be set up ({first})") from exc
    batch_class = cls.world_batch()
    reason = batch_refusal(cls, programs)
    if batch_class is None or reason is not None:
        raise NotBatched(str(reason))
    return batch_class, programs


class _Variant:
    """One variant's session and how far it got."""

    def __init__(self, loaded: LoadedScenario, session: Session) -> None:
        self.loaded = loaded
        self.session = session
        self.steps: Steps = session.advance(pause=True)
        self.result: RunResult | None = None

    def resume(self) -> bool:
        """Run up to the next engine step (True) or to the end (False: ``result`` is set, the trace finished)."""
        try:
            while next(self.steps) != BEFORE_STEP:
                pass
            return True
        except StopIteration as done:
            result = done.value
        except EngineFailure as exc:
            result = failure_result(self.session, self.loaded, exc)
        self.result = finish_trace(self.session.trace, result)
        return False


def run_batch(
    loads: Sequence[LoadedScenario],
    backend_name: str,
    out_dirs: Sequence[Path | None],
    progress: Callable[[int, int], None] | None = None,
    budgets: Sequence[float | None] | None = None,
    force: bool = True,
    record_every: int = 1,
) -> list[RunResult]:
    """Run ``loads`` as one batch on ``backend_name``, each with its trace in its ``out_dirs`` entry (None: no
    trace); one result per variant, in order. ``progress(k, n)``: the batch's steps done of its longest
    variant's. Variants that do not batch raise :class:`NotBatched` before anything runs."""
    started = wallclock.perf_counter()
    batch_class, programs = prepare(loads, backend_name)
    total = max(p.steps for p in programs)
    with contextlib.ExitStack() as stack:
        for loaded, out_dir in zip(loads, out_dirs, strict=True):
            if out_dir is not None:
                try:
                    out_dir.mkdir(parents=True, exist_ok=True)
                except OSError as exc:
                    raise write_error(exc, f"the trace folder {out_dir}") from exc
                stack.enter_context(Claim(trace_path(out_dir, loaded, backend_name), force=force))
        batch = stack.enter_context(batch_class([p.world for p in programs]))
        interrupts.check()  # building a big batch can take long
        stack.enter_context(interrupts.deferred())
        variants: list[_Variant] = []
        for i, (loaded, program, view) in enumerate(zip(loads, programs, batch.views, strict=True)):
            trace = None
            if out_dirs[i] is not None:
                trace = stack.enter_context(open_trace(Path(str(out_dirs[i])), loaded, program, view, record_every))
                start_trace(trace, loaded, program)
            budget = (budgets[i] if budgets is not None else None) or loaded.model.world.budget
            watchdog = None if budget is None else Watchdog(budget, program.steps, program.world.dt, started,
                                                            backend_name)  # fmt: skip
            variants.append(_Variant(loaded, Session(program, view, trace, None, record_every, watchdog)))
        active = [v.resume() for v in variants]
        done = 0
        while any(active):
            batch.step_all(active)  # a world's failure is raised by its view's step(), in its session
            done += 1
            for i, variant in enumerate(variants):
                if active[i]:
                    active[i] = variant.resume()
            if progress is not None:
                progress(done, total)
        if progress is not None and done < total:
            progress(total, total)  # every variant ended early
    return [_result(v) for v in variants]


def _result(variant: _Variant) -> RunResult:
    if variant.result is None:  # pragma: no cover - every variant ran to its end above
        raise RuntimeError(f"variant {variant.loaded.variant} has no result")
    return variant.result
