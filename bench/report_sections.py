"""bench/results.md's sections on the step loop's overhead, scaling, the trace, memory and batches, and what
remains of the overhead (the figures' tables and their readings)."""

from __future__ import annotations

import importlib
from collections.abc import Sequence

from .batch import BatchFigures
from .measure import RAW_LOOPS
from .memory import MemoryFigures
from .overhead import PROCESS, BackendFigures
from .scaling import FULL_STEPS_UP_TO, MIN_STEPS_BEYOND, Limit, SizeFigures, marginal


def fmt(x: float, digits: int = 3) -> str:
    return "n/a" if x != x else f"{x:.{digits}f}"  # noqa: PLR0124 - NaN check


def floor_section(figs: Sequence[BackendFigures]) -> list[str]:
    """What reading every body costs the hand-written loop, and the runner without a trace against it."""
    if not figs:
        return []
    reads = ", ".join(f"{f.backend} {f.ratio('raw+reads'):.2f}" for f in figs)
    untraced = ", ".join(f"{f.backend} {f.ratio('runner', 'raw+reads'):.2f}" for f in figs)
    raw_targets = [(f, t) for f in figs if (t := raw_target(f.backend)) is not None]
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


def cause(f: BackendFigures, runs: str = "trace", base: str = "raw+reads") -> str:
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


def reads_section(figs: Sequence[BackendFigures]) -> list[str]:
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


def overhead_section(figs: Sequence[BackendFigures]) -> list[str]:
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
    return [*out, "", *reads_section(figs)]


def scaling_section(figs: Sequence[SizeFigures], limits: Sequence[Limit], seconds: float | None) -> list[str]:
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


def trace_section(overhead: Sequence[BackendFigures], scaling: Sequence[SizeFigures]) -> list[str]:
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


def memory_section(figs: Sequence[MemoryFigures]) -> list[str]:
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


def batch_section(b: BatchFigures) -> list[str]:
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


def raw_target(backend: str) -> float | None:
    """An engine's own target for runner with the full trace / the raw loop without reads, when its loop
    (bench/raw_<name>.py) states one as ``TARGET_RATIO_RAW``."""
    module = RAW_LOOPS.get(backend)
    target = getattr(importlib.import_module(module), "TARGET_RATIO_RAW", None) if module else None
    return float(target) if target is not None else None
