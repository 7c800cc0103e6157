"""bench/results.md: the machine, the versions, the sizes, every figure, and each target met or not."""

from __future__ import annotations

import datetime as dt
import os
import platform
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from backends.registry import list_backends

from . import build as bld
from . import encoding as enc
from . import ray_cluster, seed_loop
from . import robot as rbt
from . import startup as sup
from . import worlds as wb
from .batch import BatchFigures
from .known_causes import KNOWN_CAUSES
from .memory import MemoryFigures
from .overhead import PROCESS, BackendFigures
from .report_sections import (
    batch_section,
    cause,
    floor_section,
    memory_section,
    overhead_section,
    raw_target,
    scaling_section,
    trace_section,
)
from .scaling import Limit, SizeFigures, marginal

TARGET_RATIO = 1.10  # runner with the full trace / the hand-written loop that reads every body each step
TARGET_MEMORY = 1.10
TARGET_CEILING = 0.9  # -j 2 speed-up / the pure loop's speed-up on 2 processes
TARGET_LINEAR = 1.5  # marginal runner cost per body, 100->1000 over 10->100: at most this


@dataclass
class Results:
    command: str
    sizes: dict[str, Any]
    overhead: list[BackendFigures] = field(default_factory=list)
    scaling: list[SizeFigures] = field(default_factory=list)
    scaling_limits: list[Limit] = field(default_factory=list)
    section_seconds: dict[str, float] = field(default_factory=dict)  # wall time of the sections that record it
    memory: list[MemoryFigures] = field(default_factory=list)
    batch: BatchFigures | None = None
    encoding: list[enc.EncodingFigures] = field(default_factory=list)
    build: list[bld.BuildFigures] = field(default_factory=list)
    robot: list[rbt.RobotFigures] = field(default_factory=list)
    startup: sup.StartupFigures | None = None
    seed: seed_loop.SeedFigures | None = None
    ray: ray_cluster.RayFigures | None = None
    worlds: list[wb.WorldsFigures] = field(default_factory=list)
    wrapper_us: float = 0.0
    load: tuple[float, float] = (0.0, 0.0)  # 1-minute load average at the start and the end
    wall_seconds: float = 0.0


def _machine() -> list[str]:
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = []
    for dist in (*(e.distribution for e in list_backends()), "numpy", "mcap", "ray"):
        try:
            versions.append(f"{dist} {version(dist)}")
        except PackageNotFoundError:
            versions.append(f"{dist} not installed")
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=False,
                                cwd=Path(__file__).parent).stdout.strip()  # fmt: skip
    except OSError:
        commit = ""
    return [
        f"- date: {dt.datetime.now(dt.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}",
        f"- machine: {cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}",
        f"- Python {platform.python_version()}; {', '.join(versions)}",
        f"- commit: {commit or '?'} (plus uncommitted changes, if any)",
    ]


def _met(ok: bool) -> str:
    return "met" if ok else "**not met**"


def render(r: Results) -> str:
    out = ["# Benchmark results", "", *_machine(),
           f"- load average (1 min) at start {r.load[0]:.2f}, at end {r.load[1]:.2f}: figures taken under load are "
           "noisy; the targets are ratios of runs interleaved in one session, which load affects less",
           f"- command: `{r.command}`; whole benchmark {r.wall_seconds / 60:.1f} min",
           f"- sizes: {', '.join(f'{k} {v}' for k, v in r.sizes.items())}",
           f"- instrumentation: wrapped methods add {r.wrapper_us:.2f} us per call (bench/instrument.py)",
           ""]  # fmt: skip
    out += _targets(r)
    if r.overhead:
        out += overhead_section(r.overhead)
    if r.scaling:
        out += scaling_section(r.scaling, r.scaling_limits, r.section_seconds.get("scaling"))
    out += trace_section(r.overhead, r.scaling)
    if r.memory:
        out += memory_section(r.memory)
    if r.batch is not None:
        out += batch_section(r.batch)
    if r.encoding:
        out += enc.render(r.encoding)
    if r.build:
        out += bld.render(r.build)
    if r.robot:
        out += rbt.render(r.robot)
    out += seed_loop.render(r.seed)
    out += sup.render(r.startup)
    out += wb.render(r.worlds, wb.GPU_NOTE)
    causes = [f"- {c}" for c in KNOWN_CAUSES]
    out += ["## What remains, and why (profiling)", "", *floor_section(r.overhead), *causes, ""]
    return "\n".join(out) + "\n"


def _targets(r: Results) -> list[str]:
    rows = ["## Targets", "", "| target | measured | status | where the time goes (beyond the target's loop) |",
            "|---|---|---|---|"]  # fmt: skip
    for f in r.overhead:
        ratio = f.ratio("runner+trace", "raw+reads")
        rows.append(f"| overhead, {f.backend}, {f.bodies} boxes, full trace: runner/(raw+reads) <= {TARGET_RATIO} "
                    f"| {ratio:.2f} | {_met(ratio <= TARGET_RATIO)} | {cause(f)} |")  # fmt: skip
        target = raw_target(f.backend)
        if target is not None:
            ratio = f.ratio("runner+trace")
            rows.append(f"| overhead, {f.backend}, {f.bodies} boxes, full trace: runner/raw <= {target} "
                        f"| {ratio:.2f} | {_met(ratio <= target)} | {cause(f, base='raw')} |")  # fmt: skip
        if PROCESS in f.seconds:
            ratio = f.ratio(PROCESS, "raw+reads")
            rows.append(f"| overhead, {f.backend}, {f.bodies} boxes, full trace written by a second process "
                        f"(`--trace-process`): runner/(raw+reads) <= {TARGET_RATIO} | {ratio:.2f} "
                        f"| {_met(ratio <= TARGET_RATIO)} | {cause(f, 'process')} |")  # fmt: skip
    for backend in sorted({s.backend for s in r.scaling}):
        steps = marginal([s for s in r.scaling if s.backend == backend])
        if len(steps) >= 2 and steps[0][2] > 0:
            growth = steps[-1][2] / steps[0][2]
            rows.append(f"| runner's own cost linear in bodies ({backend}): marginal cost per body "
                        f"{steps[-1][0]}->{steps[-1][1]} / {steps[0][0]}->{steps[0][1]} <= {TARGET_LINEAR} "
                        f"| {growth:.2f} | {_met(growth <= TARGET_LINEAR)} | |")  # fmt: skip
    rows += _reach(r.scaling, r.scaling_limits)
    rows += enc.targets(r.encoding)
    rows += bld.targets(r.build)
    rows += seed_loop.targets(r.seed)
    rows += ray_cluster.targets(r.ray)
    for backend in sorted({m.backend for m in r.memory}):
        runs = sorted((m for m in r.memory if m.backend == backend), key=lambda m: m.duration)
        if len(runs) >= 2:
            growth = runs[-1].peak_kb / runs[0].peak_kb
            rows.append(f"| peak memory {runs[-1].duration:g} s / {runs[0].duration:g} s ({backend}) "
                        f"<= {TARGET_MEMORY} "
                        f"| {growth:.3f} | {_met(growth <= TARGET_MEMORY)} | |")  # fmt: skip
    if r.batch is not None and 2 in r.batch.seconds:
        b = r.batch
        s, ceiling, share = b.speedup(2), b.ceiling_speedup(2), b.share_of_ceiling(2)
        serial = b.serial_seconds()
        rest = (f"the command's start-up and loading of every variant (`scenario validate` on the same files) take "
                f"{serial:.2f} s, {serial / b.median(1):.0%} of -j 1's time, which -j cannot divide; "
                if serial == serial else "")  # fmt: skip
        contention, ideal = b.contention(2), b.ideal(2)
        if contention == contention:
            rest += (f"side by side the cases took {contention:.2f}x their time alone (their summed wall time, "
                     f"cost.json: shared caches and memory, which the pure loop does not touch); with none of "
                     f"that, -j 2 would take {ideal:.2f} s (the serial part plus the larger of half the cases' "
                     f"time and the longest case) against {b.median(2):.2f} s measured; ")  # fmt: skip
        rows.append(f"| batch -j 2 reaches >= {TARGET_CEILING:.0%} of the machine's parallel ceiling | {share:.0%} "
                    f"({s:.2f}x of {ceiling:.2f}x) | {_met(share >= TARGET_CEILING)} | the ceiling: a pure-Python loop "
                    f"split over 2 processes; {rest}load average {r.load[0]:.1f}-{r.load[1]:.1f} on "
                    f"{os.cpu_count()} cores |")  # fmt: skip
    extra = [*rbt.target_rows(r.robot), *sup.target_rows(r.startup), *wb.target_rows(r.worlds)]
    for goal, measured, ok, where in extra:
        rows.append(f"| {goal} | {measured} | {_met(ok)} | {where} |")
    return [*rows, ""]


def _reach(figs: Sequence[SizeFigures], limits: Sequence[Limit]) -> list[str]:
    """Target rows: each backend's table reaches the largest size asked (10,000 bodies by default)."""
    if not figs and not limits:
        return []
    largest = max([s.bodies for s in figs] + [lim.bodies for lim in limits])
    rows = []
    for backend in sorted({s.backend for s in figs} | {lim.backend for lim in limits}):
        top = [s for s in figs if s.backend == backend and s.bodies == largest]
        stop = [lim for lim in limits if lim.backend == backend]
        if top:
            s = top[0]
            rows.append(f"| scaling table to {largest:,} bodies ({backend}) | runner {s.runner_us_per_body:.2f} "
                        f"us/body/step, {s.kib_per_body:.1f} KiB/body, trace {s.trace_bytes_per_body_step:.1f} "
                        f"bytes/body/step | met | section 2 |")  # fmt: skip
        else:
            reached = max((s.bodies for s in figs if s.backend == backend), default=0)
            why = stop[0].reason if stop else "not run"
            rows.append(f"| scaling table to {largest:,} bodies ({backend}) | up to {reached:,} "
                        f"| **not met** | at {stop[0].bodies if stop else largest:,} bodies: {why} |")  # fmt: skip
    return rows


def append_notes(text: str, notes: Sequence[str]) -> str:
    if not notes:
        return text
    return text + "\n## Notes\n\n" + "\n".join(f"- {n}" for n in notes) + "\n"
