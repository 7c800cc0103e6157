"""One measured run: the runner (instrumented, see bench/instrument.py) or a hand-written loop."""

from __future__ import annotations

import gc
import importlib
import importlib.util
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from backends.registry import create_backend, get_backend, list_backends
from backends.types import CompiledWorld
from runner.compile.program import build_program
from runner.language.load import LoadedScenario, load_scenario
from runner.sim.assertions import AssertionTracker
from runner.sim.run import run_loaded
from runner.sim.session import Session
from runner.trace.process import BackgroundTraceWriter
from runner.trace.writer import TraceWriter

from . import instrument as ins
from .raw_common import RawTiming, time_loop

PILE = Path(__file__).parent / "scenarios" / "pile.yaml"


def _raw_loops() -> dict[str, str]:
    """Each registered engine's hand-written loop: the module bench/raw_<name>.py (its ``LOOP``), when it exists."""
    names = (e.name for e in list_backends())
    return {name: f"bench.raw_{name}" for name in names if importlib.util.find_spec(f"bench.raw_{name}") is not None}


#: Registry name -> the module of its hand-written loop (imported, with its engine, only when run).
RAW_LOOPS = _raw_loops()


def pile(counts: tuple[int, int, int], duration: float, dt: float = 0.004) -> LoadedScenario:
    nx, ny, nz = counts
    overrides = (("params.nx", nx), ("params.ny", ny), ("params.nz", nz), ("world.duration", duration),
                 ("world.dt", dt))  # fmt: skip
    return load_scenario(PILE, None, overrides)


@dataclass(frozen=True)
class RunnerTiming:
    seconds: float  # run_loaded, wall
    steps: int
    status: str
    engine_build: float  # the adapter's constructor (and settings(), close())
    engine_step: float  # Backend.step
    engine_reads: float  # body_states, joint_states, contacts
    engine_states: float  # body_states, joint_states: the part of the reads the hand-written loop also makes
    engine_contacts: float  # contacts (read for the trace's /contacts, and for contact events and assertions)
    engine_inputs: float
    trace: float  # every TraceWriter method
    assertions: float  # AssertionTracker.on_step
    detect: float  # Session._detect (collision solids and contact events)
    wrapped_calls: int
    trace_bytes: int

    @property
    def runner_own(self) -> float:
        """Everything but the engine and the trace: compiling, the step loop's bookkeeping, assertions."""
        return self.seconds - self.engine_build - self.engine_step - self.engine_reads - self.engine_inputs - self.trace


def run_runner(loaded: LoadedScenario, backend: str, out_dir: Path | None, trace_process: bool = False) -> RunnerTiming:
    cls = get_backend(backend)
    targets: dict[str, tuple[type, tuple[str, ...]]] = {
        "engine": (cls, ins.ENGINE_STEP + ins.ENGINE_READS + ins.ENGINE_INPUTS + ins.ENGINE_SETUP),
        "trace": (TraceWriter, ins.TRACE_METHODS),
        "assert": (AssertionTracker, ("on_step",)),
        "detect": (Session, ("_detect",)),
    }
    # the writer in a second process (--trace-process): its calls cost the run's process
    targets["trace-process"] = (BackgroundTraceWriter, ins.TRACE_METHODS)
    gc.collect()
    with ins.timed(targets) as split:
        start = time.perf_counter()
        result = run_loaded(loaded, backend, out_dir, trace_process=trace_process)
        seconds = time.perf_counter() - start
    size = os.path.getsize(result.trace) if result.trace else 0
    return RunnerTiming(
        seconds=seconds,
        steps=result.steps,
        status=result.status,
        engine_build=split.total("engine", ins.ENGINE_SETUP),
        engine_step=split.total("engine", ins.ENGINE_STEP),
        engine_reads=split.total("engine", ins.ENGINE_READS),
        engine_states=split.total("engine", ("body_states", "joint_states")),
        engine_contacts=split.total("engine", ("contacts",)),
        engine_inputs=split.total("engine", ins.ENGINE_INPUTS),
        trace=split.total("trace") + split.total("trace-process"),
        assertions=split.total("assert"),
        detect=split.total("detect"),
        wrapped_calls=sum(split.calls.values()),
        trace_bytes=size,
    )


def adapter_settings(backend: str, world: CompiledWorld) -> dict[str, Any]:
    adapter = create_backend(backend, world)
    try:
        return adapter.settings()
    finally:
        adapter.close()


def run_raw(backend: str, world: CompiledWorld, settings: dict[str, Any], steps: int, read: bool) -> RawTiming:
    make = importlib.import_module(RAW_LOOPS[backend]).LOOP
    gc.collect()
    return time_loop(make, world, settings, steps, read)


def world_of(loaded: LoadedScenario) -> tuple[CompiledWorld, int]:
    program = build_program(loaded)
    return program.world, program.steps


def final_from_trace(path: str) -> np.ndarray:
    """(N, 13) final rows of a trace's /bodies (resolution 1e-9)."""
    from reports.trace_reader import read_trace

    trace = read_trace(path)
    rows = [np.concatenate([s.pos[-1], s.quat[-1], s.vel[-1], s.angvel[-1]]) for s in trace.bodies.values()]
    return np.array(rows)
