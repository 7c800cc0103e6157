"""bench/results.md: the machine, the versions, the sizes, every figure, and each target met or not."""

from __future__ import annotations

import datetime as dt
import importlib
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
from .measure import RAW_LOOPS
from .memory import MemoryFigures
from .overhead import PROCESS, BackendFigures
from .scaling import FULL_STEPS_UP_TO, MIN_STEPS_BEYOND, Limit, SizeFigures, marginal

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


def _f(x: float, digits: int = 3) -> str:
    return "n/a" if x != x else f"{x:.{digits}f}"  # noqa: PLR0124 - NaN check


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
        out += _overhead(r.overhead)
    if r.scaling:
        out += _scaling(r.scaling, r.scaling_limits, r.section_seconds.get("scaling"))
    out += _trace(r.overhead, r.scaling)
    if r.memory:
        out += _memory(r.memory)
    if r.batch is not None:
        out += _batch(r.batch)
    if r.encoding:
        out += enc.render(r.encoding)
    if r.build:
        out += bld.render(r.build)
    if r.robot:
        out += rbt.render(r.robot)
    out += seed_loop.render(r.seed)
    out += sup.render(r.startup)
    out += wb.render(r.worlds, wb.GPU_NOTE)
    out += ["## What remains, and why (profiling)", "", *_floor(r.overhead), *(f"- {c}" for c in KNOWN_CAUSES), ""]
    return "\n".join(out) + "\n"


def _targets(r: Results) -> list[str]:
    rows = ["## Targets", "", "| target | measured | status | where the time goes (beyond the target's loop) |",
            "|---|---|---|---|"]  # fmt: skip
    for f in r.overhead:
        ratio = f.ratio("runner+trace", "raw+reads")
        rows.append(f"| overhead, {f.backend}, {f.bodies} boxes, full trace: runner/(raw+reads) <= {TARGET_RATIO} "
                    f"| {ratio:.2f} | {_met(ratio <= TARGET_RATIO)} | {_cause(f)} |")  # fmt: skip
        target = _raw_target(f.backend)
        if target is not None:
            ratio = f.ratio("runner+trace")
            rows.append(f"| overhead, {f.backend}, {f.bodies} boxes, full trace: runner/raw <= {target} "
                        f"| {ratio:.2f} | {_met(ratio <= target)} | {_cause(f, base='raw')} |")  # fmt: skip
        if PROCESS in f.seconds:
            ratio = f.ratio(PROCESS, "raw+reads")
            rows.append(f"| overhead, {f.backend}, {f.bodies} boxes, full trace written by a second process "
                        f"(`--trace-process`): runner/(raw+reads) <= {TARGET_RATIO} | {ratio:.2f} "
                        f"| {_met(ratio <= TARGET_RATIO)} | {_cause(f, 'process')} |")  # fmt: skip
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


def _raw_target(backend: str) -> float | None:
    """An engine's own target for runner with the full trace / the raw loop without reads, when its loop
    (bench/raw_<name>.py) states one as ``TARGET_RATIO_RAW``."""
    module = RAW_LOOPS.get(backend)
    target = getattr(importlib.import_module(module), "TARGET_RATIO_RAW", None) if module else None
    return float(target) if target is not None else None
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


def _floor(figs: Sequence[BackendFigures]) -> list[str]:
    """What reading every body costs the hand-written loop, and the runner without a trace against it."""
    if not figs:
        return []
    reads = ", ".join(f"{f.backend} {f.ratio('raw+reads'):.2f}" for f in figs)
    untraced = ", ".join(f"{f.backend} {f.ratio('runner', 'raw+reads'):.2f}" for f in figs)
    raw_targets = [(f, t) for f in figs if (t := _raw_target(f.backend)) is not None]
    against_raw = "".join(
        f" On {f.backend} the target against the loop without reads ({t:.2f}) leaves "
        f"{(t - f.ratio('raw+reads')) * 100:.0f} % of the raw loop's time for everything but the state reads."
        for f, t in raw_targets
    )
    return [
        f"- Reading every body's state each step is itself a cost the raw loop does not pay: the hand-written "
        f"loop that also reads them (the 1.10 target's loop) runs at {reads} times the raw loop.{against_raw} "
        f"Against the loop with reads, the runner without a trace runs at {untraced}; what is beyond it is the "
        f"trace and reading contacts for it.",
    ]


def _cause(f: BackendFigures, runs: str = "trace", base: str = "raw+reads") -> str:
    """The parts of a traced run beyond the hand-written loop ``base`` (``raw+reads``: it also reads every
    body's state each step; ``raw``: it does not), largest first, in ms per step and share of the excess
    (``runs``: "trace", the writer in the run's process, or "process", the writer in a second process)."""
    per = 1e3 / f.steps
    loop_reads = f.median("raw+reads") - f.median("raw") if base == "raw+reads" else 0.0
    parts = {
        "adapter step beyond raw": f.part("engine_step", runs) - f.median("raw") + f.part("engine_build", runs),
        "state reads" + (" beyond the loop's" if base == "raw+reads" else ""): f.part("engine_states", runs)
        - loop_reads,
        "contact reads": f.part("engine_contacts", runs),
        "trace" if runs == "trace" else "sending the trace": f.part("trace", runs),
        "assertions": f.part("assertions", runs),
        "collision events": f.part("detect", runs),
        "runner, other": f.part("runner_own", runs) - f.part("assertions", runs) - f.part("detect", runs),
    }
    excess = f.median("runner+trace" if runs == "trace" else PROCESS) - f.median(base)
    ranked = sorted(parts.items(), key=lambda kv: -kv[1])[:3]
    return "; ".join(f"{k} {v * per:.2f} ms/step ({v / excess:.0%})" for k, v in ranked if excess > 0)


def _reads(figs: Sequence[BackendFigures]) -> list[str]:
    """Reads per body per step: the hand-written loop's (raw+reads - raw) and the adapter's, split."""
    out = ["Reads, us per body per step (medians; the adapter's from the traced runs): *loop*: what reading every "
           "body's pose and velocity adds to the hand-written loop (raw+reads - raw, the engine's cheapest path "
           "written by hand); *states*: the adapter's `body_states()` and `joint_states()`; *contacts*: its "
           "`contacts()` (every touching pair with its points, depth and normal force, for the trace's "
           "/contacts).", "",
           "| backend | loop | adapter: states | adapter: contacts | adapter: all reads |", "|---|---|---|---|---|"]
    for f in figs:
        per = 1e6 / f.steps / f.bodies
        out.append(f"| {f.backend} | {(f.median('raw+reads') - f.median('raw')) * per:.2f} "
                   f"| {f.part('engine_states') * per:.2f} | {f.part('engine_contacts') * per:.2f} "
                   f"| {f.part('engine_reads') * per:.2f} |")  # fmt: skip
    return [*out, ""]


def _overhead(figs: Sequence[BackendFigures]) -> list[str]:
    n = len(figs[0].seconds.get("raw", []))
    out = ["## 1. Overhead: runner vs a hand-written loop", "",
           f"`bench/scenarios/pile.yaml`, medians of {n} interleaved repetitions (wall seconds, build included). "
           "*raw*: the engine built and stepped by hand with the adapter's settings (bench/raw_*.py), no reads; "
           "*raw+reads*: the same, reading every body's pose and velocity each step; *same physics*: largest "
           "distance between the raw loop's and the runner's final positions (the trace's resolution is 1e-9 m).", "",
           "| backend | boxes | steps | raw | raw+reads | runner + trace | runner, no trace | ratio (trace) "
           "| ratio (no trace) | ratio vs raw+reads (trace) | ratio vs raw+reads (no trace) | same physics (m) "
           "| statuses |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    process = [f for f in figs if PROCESS in f.seconds]
    for f in figs:
        out.append(f"| {f.backend} | {f.bodies} | {f.steps} | {f.median('raw'):.2f} | {f.median('raw+reads'):.2f} "
                   f"| {f.median('runner+trace'):.2f} | {f.median('runner'):.2f} | {f.ratio('runner+trace'):.2f} "
                   f"| {f.ratio('runner'):.2f} | {f.ratio('runner+trace', 'raw+reads'):.2f} "
                   f"| {f.ratio('runner', 'raw+reads'):.2f} | {f.same_physics:.1e} "
                   f"| {', '.join(sorted(f.statuses))} |")  # fmt: skip
    if process:
        out += ["", "With the trace written by a second process (`run_loaded(..., trace_process=True)`):", "",
                "| backend | runner + trace in a process (s) | ratio | trace calls in the run's process (ms/step) |",
                "|---|---|---|---|"]  # fmt: skip
        for f in process:
            mode = PROCESS
            out.append(f"| {f.backend} | {f.median(mode):.2f} | {f.ratio(mode):.2f} "
                       f"| {f.part('trace', 'process') * 1e3 / f.steps:.3f} |")  # fmt: skip
    out += ["", "Where the runner's time goes (ms per step, medians of the traced runs; *engine step* is the "
            "adapter's `step()`, which also does the adapter's per-step bookkeeping):", "",
            "| backend | raw step | engine step | engine reads | trace | assertions | collision events "
            "| runner, other | build (s) |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for f in figs:
        per = 1e3 / f.steps
        other = f.part("runner_own") - f.part("assertions") - f.part("detect")
        out.append(f"| {f.backend} | {f.median('raw') * per:.3f} | {f.part('engine_step') * per:.3f} "
                   f"| {f.part('engine_reads') * per:.3f} | {f.part('trace') * per:.3f} "
                   f"| {f.part('assertions') * per:.3f} | {f.part('detect') * per:.3f} | {other * per:.3f} "
                   f"| {f.part('engine_build'):.2f} |")  # fmt: skip
    return [*out, "", *_reads(figs)]


def _scaling(figs: Sequence[SizeFigures], limits: Sequence[Limit], seconds: float | None) -> list[str]:
    sizes = sorted({s.bodies for s in figs} | {lim.bodies for lim in limits})
    took = f" The section took {seconds / 60:.1f} min." if seconds is not None else ""
    out = [f"## 2. Scaling: {', '.join(f'{n:,}' for n in sizes)} bodies", "",
           "One run each, trace on, each in a child process. *engine*: the adapter's step, reads and inputs; "
           "*runner*: everything but the engine and the trace writer; *build*: the adapter's constructor; "
           "*memory*: the child's peak RSS after the run minus its RSS with the engine imported, per body (at "
           "small sizes mostly the run's fixed cost: the marginal table gives the cost of a body); "
           f"*trace*: bytes per body per step (the ground included). Beyond {FULL_STEPS_UP_TO:,} bodies the "
           f"runs are shorter in proportion, but at least {MIN_STEPS_BEYOND} steps (a run's fixed O(bodies) work over "
           f"25 steps read as a per-step cost).{took}", "",
           "| backend | bodies | steps | engine ms/step | trace ms/step | runner ms/step | runner us/body/step "
           "| trace us/body/step | memory KiB/body | trace bytes/body/step | build (s) |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for s in figs:
        out.append(f"| {s.backend} | {s.bodies:,} | {s.timing.steps} | {s.engine_ms:.3f} | {s.trace_ms:.3f} "
                   f"| {s.runner_ms:.3f} | {s.runner_us_per_body:.2f} | {1e3 * s.trace_ms / s.bodies:.2f} "
                   f"| {s.kib_per_body:.1f} | {s.trace_bytes_per_body_step:.1f} "
                   f"| {s.timing.engine_build:.2f} |")  # fmt: skip
    for lim in limits:
        out.append(f"| {lim.backend} | {lim.bodies:,} | | {lim.reason} | | | | | | | |")
    out += [
        "",
        "Marginal cost per added body per step (us), and memory per added body (KiB): linear growth keeps them "
        "constant.",
        "",
        "| backend | sizes | runner | trace | engine | memory |",
        "|---|---|---|---|---|---|",
    ]
    for backend in sorted({s.backend for s in figs}):
        mine = sorted((s for s in figs if s.backend == backend), key=lambda s: s.bodies)
        mem = [(b.peak_kib - a.peak_kib) / (b.bodies - a.bodies) for a, b in zip(mine, mine[1:], strict=False)]
        for (a, b, run_), (_, _, tr), (_, _, eng), kib in zip(
            marginal(mine), marginal(mine, "trace_ms"), marginal(mine, "engine_ms"), mem, strict=True
        ):
            out.append(f"| {backend} | {a:,} -> {b:,} | {run_ * 1e3:.2f} | {tr * 1e3:.2f} | {eng * 1e3:.2f} "
                       f"| {kib:.1f} |")  # fmt: skip
    return [*out, ""]


def _trace(overhead: Sequence[BackendFigures], scaling: Sequence[SizeFigures]) -> list[str]:
    out = [
        "## 3. Trace: size and share of the run time",
        "",
        "| run | bodies | steps | bytes | bytes/body/step | trace time share |",
        "|---|---|---|---|---|---|",
    ]
    for f in overhead:
        t = f.parts[len(f.parts) // 2] if f.parts else None
        if t is not None:
            share = f.part("trace") / f.median("runner+trace")
            out.append(f"| overhead, {f.backend} | {f.bodies + 1} | {t.steps} | {t.trace_bytes} "
                       f"| {t.trace_bytes / ((f.bodies + 1) * t.steps):.1f} | {share:.1%} |")  # fmt: skip
    for s in scaling:
        t = s.timing
        out.append(f"| scaling, {s.backend} | {s.bodies + 1} | {t.steps} | {t.trace_bytes} "
                   f"| {t.trace_bytes / ((s.bodies + 1) * t.steps):.1f} | {t.trace / t.seconds:.1%} |")  # fmt: skip
    out += ["", "Bodies include the ground plane (it is recorded like any body)."]
    return [*out, ""]


def _memory(figs: Sequence[MemoryFigures]) -> list[str]:
    out = [
        "## 4. Memory: peak RSS of a whole run (child process, trace on)",
        "",
        "| backend | boxes | simulated s | steps | peak RSS (MiB) | trace (MB) |",
        "|---|---|---|---|---|---|",
    ]
    for m in figs:
        out.append(f"| {m.backend} | {m.bodies} | {m.duration:g} | {m.steps} | {m.peak_kb / 1024:.1f} "
                   f"| {m.trace_bytes / 1e6:.1f} |")  # fmt: skip
    return [*out, ""]


def _batch(b: BatchFigures) -> list[str]:
    out = ["## 5. Batch: many files and variants in parallel", "",
           f"{b.files} files ({b.cases} cases, every variant) on {b.backend}, via {b.via}, each a whole command "
           f"(start-up included); exit codes seen: {sorted(b.exit_codes)}.", "",
           "*pure loop*: the same number of processes sharing a fixed pure-Python loop (no I/O, nothing shared), "
           "run after each batch command: what the machine gives perfectly parallel work.", "",
           "| -j | runs (s) | median (s) | speed-up over -j 1 | pure loop (s) | pure loop speed-up |",
           "|---|---|---|---|---|---|"]  # fmt: skip
    for j in sorted(b.seconds):
        runs = ", ".join(f"{s:.2f}" for s in b.seconds[j])
        loops = ", ".join(f"{s:.2f}" for s in b.ceiling.get(j, []))
        out.append(f"| {j} | {runs} | {b.median(j):.2f} | {b.speedup(j):.2f} | {loops} | {b.ceiling_speedup(j):.2f} |")
    if b.case_sum:
        out += ["", "The cases' own wall time (their cost.json files), summed and the longest, per run: "
                    + "; ".join(f"-j {j}: " + ", ".join(f"{t:.2f} ({m:.2f})" for t, m in
                                                       zip(b.case_sum[j], b.case_max[j], strict=True))
                                for j in sorted(b.case_sum))
                    + "."]  # fmt: skip
    if b.serial:
        out += ["", f"The serial part: `scenario validate` on the same files (the command's start-up and the loading "
                    f"and validation of every variant, which every -j pays once) takes "
                    f"{', '.join(f'{x:.2f}' for x in b.serial)} s (median {b.serial_seconds():.2f} s)."]  # fmt: skip
    return [*out, ""]


#: Causes found by profiling (cProfile, this instrumentation and old/new adapters interleaved in one
#: process on the 100-box pile), for "what remains". Every item was measured; none is a guess.
KNOWN_CAUSES = (
    "The trace in the run's process: /tf and /bodies (protobuf bytes from templates, 20 doubles per body) and "
    "/contacts (one templated message per touching pair), then MCAP chunks them with zstd: 0.09 ms per step "
    "for 100 bodies alone, 0.10-0.14 ms inside runs (the engine's step evicts the caches between steps; CPU "
    "time, medians of 3 interleaved; what is in it: below). "
    "`--trace-process` moves formatting and writing to a second process; the run pays 0.1-0.15 ms per step "
    "for it (packing a step's doubles, 16 steps per pipe write, starting the writer and waiting for it at the"
    " end). What it gains depends on a free core and varies between runs on this two-core virtual machine "
    "(compare each engine's two rows in the targets): the engine's step and reads get slower while the writer"
    " runs on the other core (shared cache and memory bandwidth), most on DART. `--record-every K` divides "
    "the trace's cost by K.",
    "Reading contacts is only needed for the trace here (the pile has no contact assertion), so the untraced "
    "runs skip it; with the trace on it is the largest read on three engines (us per body per step, CPU time"
    " inside the step loop, 100-box pile): DART 6.4 (454 points; five dartpy fields per point, each a pybind "
    "property call of 0.13-0.2 us and no batched read in dartpy 6.20: read by the properties' own getters), "
    "ODE 2.7 (413 contacts; four panda3d calls per contact, mapped unbound, plus feedback armed on each "
    "contact joint in the step), PyBullet 2.9 (400 points; getContactPoints itself builds 400 tuples of 14 "
    "fields, about 0.3 us per point, before any of ours), MuJoCo 0.7 (478 points read as arrays; the rest is"
    " grouping them per pair). The readers were sped up with the same numbers (old and new readers equal on "
    "every step of the pile; in-process, interleaved: DART -16 %, PyBullet -11 %, ODE -28 %, the kit's "
    "grouping -11 %); what is left is each binding's per-point floor.",
    "Reading states: PyBullet has no state call for several multibodies (two engine calls per base: "
    "getBasePositionAndOrientation and getBaseVelocity, about 0.5 us each; getLinkStates needs the bodies to "
    "be links of one multibody, which free boxes are not), 1.6 us per body; DART 1.9 (was 2.9): dartpy 6.20 "
    "has no world-level getter and does not bind Skeleton::Configuration, Group or LinkageCriteria, but a "
    "Chain between two skeletons' root bodies reads both skeletons' coordinates in one call, so two calls per"
    " two bodies instead of per body (backends/dart/_reads.py); MuJoCo 0.35 and ODE 1.3 read in bulk (numpy "
    "views of MjData; one datagram of float32 vectors). The hand-written loops read the same way (bench/"
    "raw_*.py), so the state reads cost the runner no more than the loop it is compared with.",
    "The runner's own work per step (runner/sim: blow-up check, energy watchdog, assertions, contact pairs, "
    "the step loop) is 0.08-0.09 ms on every engine (CPU time, traced runs, medians of 3 interleaved; it was "
    "0.15, 0.20, 0.25 and 0.28 on MuJoCo, PyBullet, DART and ODE before issue 19's first pass): the blow-up "
    "check takes one whole-array pass when every state "
    "is finite and slow (28 -> 8 us), the energy watchdog turns the angular velocity without rotation "
    "matrices (25 -> 16 us), touching pairs by name are made only when asked for, group reads index once. "
    "What is left is a few microseconds each of numpy calls on 100-element arrays and the step loop itself.",
    "MuJoCo: the pile is a small world for MuJoCo (0.37 ms per step), so any fixed Python cost per step weighs"
    " four to six times as much as on the other engines: both MuJoCo targets leave 0.04 ms (1.10 x raw+reads) "
    "and 0.11 ms (1.30 x raw) per step for everything beyond the engine, against 0.10 ms of trace (three "
    "messages of 9, 6 and 4 KB a step, a third of it the MCAP writer's zstd and copies), 0.07 ms of contacts "
    "(480 points grouped into 100 pairs: 0.04 ms of it the kit's grouping and the Contact tuples), 0.03 ms of "
    "the adapter's step (the Coulomb step's Python), 0.03 ms of state reads and 0.08 ms of the runner (energy "
    "watchdog 0.026, assertions 0.008, the step loop): CPU time, medians of 3 interleaved runs. Contacts come "
    "from MuJoCo's geom filtering (no explicit pairs since issue 19: the build is linear in the bodies, "
    "section 7).",
    "DART: the adapter's step was 2.6 x DART's own (3.1 ms against 1.2): in worlds where a pair bounces with "
    "a bounce_vel, each engine step collides first and read every contact point (five dartpy calls each) and "
    "every body's motion to find the pairs approaching below bounce_vel. DART applies restitution only when "
    "e*v > 0.1 m/s, so steps where the fastest two bodies cannot reach 0.1/e_max now read nothing "
    "(backends/dart/_gate.py: 22 of 2,500 steps read on the pile) and the step is 1.47 ms. The collision "
    "query itself (0.2-0.3 ms per step) stays in every step: DART's ODE detector keeps a per-pair contact "
    "history that every query updates and that fills in later contacts (measured: a bouncy 12-box pile gets "
    "44 points instead of 40 two steps later without it), so it is physics, not overhead, in general; on "
    "the bench pile (every pair has four points, which the history never fills in) the raw loop without it "
    "gives the same states at every step. DART's own step cannot reuse it: World.step collides again after "
    "the velocity update, inside the constraint solver.",
    "ODE: dWorldStep evicts the caches, so the same Python per step costs 2-3 times more inside the step loop"
    " than alone; what the adapter adds to the hand-written loop's step (0.3 ms per step on the pile: "
    "collision events drained from panda3d's queue and feedback armed on every contact joint, for the "
    "contacts' normal forces) is near panda3d's per-call floor (getJoint and setFeedback now mapped, not "
    "looped). The pile runs ODE with `friction_pyramid: axes, impact_cfm: false` so that contacts are made "
    "in C++ (autoCollide) as in the hand-written loop; with ODE's default settings (friction directions "
    "following the slip and the impacts' own CFM, both per contact in a Python near-callback) the runner "
    "with the full trace takes 4.3 ms per step instead of 3.2 (without a trace 3.9 instead of 2.6; CPU "
    "time, medians of 3 interleaved), about 1.9 x the hand-written loop with reads, which cannot express "
    "either.",
    "Per step, on every engine: the trace writer costs 0.10-0.14 ms in the run's thread (it was 0.13-0.18): "
    "/contacts keeps the gathered pair templates for the next step while the pairs stay the same (27 us "
    "instead of 50 for 100 pairs), /tf and /bodies are two gathers of 9 and 6 KB (20 us), and the MCAP "
    "writer's three log calls with its zstd compression (level 1, one thread) about 42 us; the bytes of "
    "every message are the format's, so no cheaper encoding is open without a format change.",
    "Batch (-j 2 on the 23 files' 44 cases, PyBullet, measured by hand beside section 5): the cases take 3.2 s "
    "of -j 1's 4.3-4.5 s (the longest two 0.55 s each); the command's start-up is 0.45 s (imports) and "
    "loading and validating every variant 0.16 s more. -j 2 uses the same CPU time as -j 1 (4.3-4.4 s user), "
    "so it duplicates no work; it took 2.63 s (1.64 x, 97 % of the pure loop's 1.69 x) and 4.67 s (0.92 x) "
    "in two runs a minute apart while other sessions loaded the two cores, and section 5's one round gave "
    "0.97 x: on this shared machine the batch figure measures the other sessions, and needs a quiet machine "
    "and several rounds.",
    "Robots (section 8, issue 29): against the engine's own loop with the same reads the runner's untraced "
    "step was 6.4 x (PyBullet) and 4.8 x (MuJoCo) on the KUKA arm, 2.5 x and 2.8 x on the quadruped (CPU "
    "time, medians of 5 interleaved, the same bench on the commit before). Profiled (cProfile and this "
    "instrumentation): the energy watchdog was the largest part, 0.13-0.16 ms per step for 8-15 links, "
    "three times the engine's step: np.cross's axis handling (moveaxis, normalize_axis_tuple) on (N, 3) "
    "arrays, a stack and an einsum for the links' full inertia tensors. Its energies are now a few "
    "whole-array products (every rotation matrix as one product of the quaternions' outer products, "
    "the COM velocity's cross product as a product with the skew matrices): 0.04-0.05 ms. PyBullet's reads "
    "(0.13-0.16 ms) read every joint with one getJointStates per multibody instead of one getJointState "
    "per joint, stream getLinkStates into one array and convert inertial frames to link frames on plain "
    "floats, rows read and written in one call each (the same operations: the same numbers); the blow-up "
    "check's common case is four whole-array calls. What remains beyond the native loop (0.09-0.23 ms "
    "per step): PyBullet's inertial-to-link-frame conversion (the runner reports link frames, the native "
    "loop takes Bullet's COM frames as they come), the energy watchdog (a dozen numpy calls, about 1 us "
    "each whatever the size), one set_motor call per servo through the contract's checks (the native loop "
    "sends one setJointMotorControlArray per robot), the assertions' expressions, and the step loop's "
    "bookkeeping (events, intervals, conditions, the progress and interruption checks): each a few "
    "microseconds, against a native step of 0.06 ms on the arm. Contacts are not read on untraced steps "
    "where nothing asks for them (issue 19). Every "
    "trace of scenarios/*.yaml and scenarios/robots/*.yaml on the four engines (56, every variant) has the "
    "same sha256 before and after these changes.",
    "Start-up (section 11, issue 29): a one-step run imports what `scenario validate` does (pydantic and "
    "the scenario language's model classes, rich, yaml) plus the engine and the trace writer (protobuf, "
    "the Foxglove schemas, mcap): validating alone costs more than importing MuJoCo, so 1.5 x is out of "
    "reach while the language is pydantic models built at import. Made lazy: the command's parser imports "
    "only the named command's module (it imported all fifteen, with reports and their readers), the exit "
    "codes no longer import the trace reader (protobuf's descriptor pool, mcap_protobuf) to recognise its "
    "error, JUnit's XML writer is imported for --junit only, and `validate` no longer imports the step "
    "loop and the verdict tables. Tried and not kept: pydantic's defer_build (the first validation builds "
    "the same schemas: the same CPU time, 0.31 s for import and first load either way).",
    "The adapters' and the runner's speed-ups behind these figures left every trace byte for byte the same "
    "(196 traces: every scenario and variant of scenarios/ on the four engines, and the bench pile, compared "
    "before and after each change with cmp): a faster read never changes the physics it reports.",
)


def append_notes(text: str, notes: Sequence[str]) -> str:
    if not notes:
        return text
    return text + "\n## Notes\n\n" + "\n".join(f"- {n}" for n in notes) + "\n"
