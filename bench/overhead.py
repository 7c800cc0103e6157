"""Benchmarks 1 and 3: the runner against hand-written loops on each engine, and what the trace costs.

Repetitions are interleaved (every mode of every backend once per round, the order rotated each
round) so that a slow spell of the machine hits all of them alike; figures are medians.
"""

from __future__ import annotations

import statistics
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runner.sim.run import trace_path

from . import measure as m

MODES = ("raw", "raw+reads", "runner+trace", "runner")
PROCESS = "runner+trace-process"  # the trace written by a second process (--trace-process)


@dataclass
class BackendFigures:
    backend: str
    bodies: int
    steps: int
    seconds: dict[str, list[float]] = field(default_factory=dict)  # mode -> per repetition
    parts: list[m.RunnerTiming] = field(default_factory=list)  # runner+trace runs
    parts_untraced: list[m.RunnerTiming] = field(default_factory=list)
    parts_process: list[m.RunnerTiming] = field(default_factory=list)
    statuses: set[str] = field(default_factory=set)
    raw_final: np.ndarray | None = None  # (N, 13) after the first raw run
    runner_final: np.ndarray | None = None  # (N, 13) from the first trace

    @property
    def same_physics(self) -> float:
        """Largest position difference between the raw loop and the runner at the end, m (trace: 1e-9)."""
        if self.raw_final is None or self.runner_final is None:
            return float("nan")
        return float(np.abs(self.raw_final[:, :3] - self.runner_final[:, :3]).max())

    def median(self, mode: str) -> float:
        return statistics.median(self.seconds[mode])

    def ratio(self, mode: str, base: str = "raw") -> float:
        return self.median(mode) / self.median(base)

    def part(self, name: str, runs: str = "trace") -> float:
        """Median seconds of one part (a RunnerTiming attribute or property) over the runs of a mode."""
        chosen = {"trace": self.parts, "none": self.parts_untraced, "process": self.parts_process}[runs]
        return statistics.median(getattr(t, name) for t in chosen)


def run(
    backends: Sequence[str],
    counts: tuple[int, int, int],
    duration: float,
    repetitions: int,
    log: Callable[[str], None] = print,
) -> list[BackendFigures]:
    loaded = m.pile(counts, duration)
    world, steps = m.world_of(loaded)
    figures = {b: BackendFigures(b, len(world.bodies) - 1, steps) for b in backends}
    settings = {b: m.adapter_settings(b, world) for b in backends}
    all_modes = (*MODES, PROCESS)
    with tempfile.TemporaryDirectory(prefix="bench-overhead-") as tmp:
        out = Path(tmp)
        for rep in range(repetitions):
            for k, backend in enumerate(backends):
                fig = figures[backend]
                turn = (rep + k) % len(all_modes)
                modes = all_modes[turn:] + all_modes[:turn]
                for mode in modes:
                    seconds = _one(mode, fig, loaded, world, settings[backend], steps, out)
                    fig.seconds.setdefault(mode, []).append(seconds)
                log(f"  overhead round {rep + 1}/{repetitions} {backend}: "
                    + ", ".join(f"{md} {fig.seconds[md][-1]:.2f}s" for md in all_modes))  # fmt: skip
    return [figures[b] for b in backends]


def _one(mode: str, fig: BackendFigures, loaded: Any, world: Any, settings: Any, steps: int, out: Path) -> float:
    if mode.startswith("raw"):
        raw = m.run_raw(fig.backend, world, settings, steps, read=mode == "raw+reads")
        if fig.raw_final is None:
            fig.raw_final = raw.final
        return raw.seconds
    traced = mode in ("runner+trace", PROCESS)
    timing = m.run_runner(loaded, fig.backend, out if traced else None, trace_process=mode == PROCESS)
    fig.statuses.add(timing.status)
    {"runner+trace": fig.parts, "runner": fig.parts_untraced, PROCESS: fig.parts_process}[mode].append(timing)
    if traced:
        path = trace_path(out, loaded, fig.backend)
        if fig.runner_final is None and mode == "runner+trace":
            fig.runner_final = m.final_from_trace(str(path))
        path.unlink(missing_ok=True)
    return timing.seconds
