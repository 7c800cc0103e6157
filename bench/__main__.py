"""``python -m bench``: run the benchmarks and write bench/results.md (see bench/README.md)."""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import time
from pathlib import Path

from backends.errors import UnsupportedFeature
from backends.registry import DEFAULT_BACKEND, check_capabilities, get_backend, is_installed, list_backends

from . import batch, build, encoding, measure, memory, overhead, ray_cluster, robot, scaling, seed_loop, startup
from . import worlds as world_batch
from .instrument import wrapper_cost
from .report import Results, append_notes, render

#: Every engine the registry lists (a fifth engine joins the benchmarks by its registry line).
#: the engines `--backend all` selects (an opt-in engine, e.g. mujoco_warp, has no hand-written loop to compare
#: with: its own benchmark is section 12)
ENGINES = tuple(e.name for e in list_backends() if not e.opt_in)


def runs_the_pile(name: str) -> bool:
    """Whether engine ``name`` runs the benchmarks' pile (bench/scenarios/pile.yaml bounces: an engine without
    restitution refuses it up front and is left out of the sections that run the pile unless named)."""
    world, _ = measure.world_of(measure.pile((1, 1, 1), 0.1))
    try:
        check_capabilities(get_backend(name), world)
    except UnsupportedFeature:
        return False
    return True


SECTIONS = ("overhead", "scaling", "memory", "batch", "encoding", "build", "robot", "seed", "startup", "ray", "worlds")


def _ints(text: str) -> list[int]:
    return [int(x) for x in text.split(",") if x.strip()]


def _floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x.strip()]


def _names(text: str) -> list[str]:
    return [x.strip() for x in text.split(",") if x.strip()]


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m bench", description=__doc__)
    p.add_argument("--out", type=Path, default=Path(__file__).parent / "results.md")
    p.add_argument("--sections", type=_names, default=list(SECTIONS), help=f"any of {','.join(SECTIONS)}")
    p.add_argument("--quick", action="store_true", help="tiny sizes: checks the machinery in about two minutes")
    p.add_argument("--backends", type=_names, default=None, help="overhead: engines (default: every installed one)")
    p.add_argument("--reps", type=int, default=3, help="overhead: interleaved repetitions (median)")
    p.add_argument("--duration", type=float, default=8.0, help="overhead: simulated seconds")
    p.add_argument("--pile", type=_ints, default=[5, 5, 4], help="overhead: nx,ny,nz boxes (default 100)")
    p.add_argument("--scaling-backends", type=_names, default=None, help="scaling: engines (default: all installed)")
    p.add_argument("--scaling-sizes", type=_ints, default=[10, 100, 1000, 10000])
    p.add_argument("--scaling-duration", type=float, default=1.0, help="simulated seconds per scaling run")
    p.add_argument("--memory-backends", type=_names, default=None, help="memory: engines (default: all installed)")
    p.add_argument("--memory-durations", type=_floats, default=[10.0, 100.0])
    p.add_argument("--memory-pile", type=_ints, default=[5, 2, 1], help="nx,ny,nz boxes for the memory runs")
    p.add_argument("--batch-backend", default=DEFAULT_BACKEND)
    p.add_argument("--batch-jobs", type=_ints, default=[1, 2])
    p.add_argument("--batch-reps", type=int, default=2)
    p.add_argument("--encoding-backends", type=_names, default=None, help="encoding: engines (default: installed)")
    p.add_argument("--encoding-duration", type=float, default=10.0, help="encoding: simulated seconds of the pile")
    p.add_argument("--encoding-reps", type=int, default=3, help="encoding: interleaved repetitions (median)")
    p.add_argument("--build-backends", type=_names, default=None, help="build: engines (default: all installed)")
    p.add_argument("--build-sizes", type=_ints, default=[100, 1000, 10000], help="build: body counts")
    p.add_argument("--robot-backends", type=_names, default=None, help="robot: engines (default: all installed)")
    p.add_argument("--robot-reps", type=int, default=5, help="robot: interleaved repetitions (median)")
    p.add_argument("--startup-reps", type=int, default=7, help="startup: interleaved rounds (median)")
    p.add_argument("--seed-duration", type=float, default=4.0, help="seed: simulated seconds of the pile on ODE")
    p.add_argument("--seed-reps", type=int, default=3, help="seed: interleaved repetitions (median)")
    p.add_argument("--worlds-sizes", type=_ints, default=list(world_batch.CPU_SIZES), help="worlds: batch sizes")
    p.add_argument("--worlds-steps", type=int, default=100, help="worlds: timed steps per batch size")
    p.add_argument("--worlds-warmup", type=int, default=50, help="worlds: steps before timing")
    return p


def _quick(a: argparse.Namespace) -> None:
    a.reps, a.duration, a.pile = 2, 0.4, [2, 2, 2]
    a.scaling_sizes, a.scaling_duration = [10, 40], 0.2
    a.memory_durations, a.memory_pile = [1.0, 4.0], [2, 1, 1]
    a.batch_reps = 1
    a.encoding_duration, a.encoding_reps = 0.4, 1
    a.build_sizes = [10, 40]
    a.seed_duration, a.seed_reps = 0.2, 1
    a.robot_reps, a.startup_reps = 1, 1
    a.worlds_sizes, a.worlds_steps, a.worlds_warmup = [1, 8], 10, 3


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    if args.quick:
        _quick(args)
    started = time.perf_counter()

    def log(text: str) -> None:
        print(f"[{time.perf_counter() - started:7.1f}s] {text}", flush=True)

    installed = [b for b in ENGINES if is_installed(b)]
    piled = [b for b in installed if runs_the_pile(b)]  # the pile's sections: engines that run it
    backends = [b for b in (args.backends or piled) if b in installed]
    args.scaling_backends = args.scaling_backends or piled
    args.memory_backends = args.memory_backends or piled
    sizes = {
        "overhead": f"{'x'.join(map(str, args.pile))} boxes, {args.duration:g} s at dt 0.004, {args.reps} reps, "
        f"{','.join(backends)}",
        "scaling": f"{args.scaling_sizes} bodies, {args.scaling_duration:g} s, {','.join(args.scaling_backends)}",
        "memory": f"{'x'.join(map(str, args.memory_pile))} boxes, {args.memory_durations} s, "
        f"{','.join(args.memory_backends)}",
        "batch": f"-j {args.batch_jobs}, {args.batch_reps} reps, {args.batch_backend}",
        "encoding": f"{'x'.join(map(str, args.pile))} boxes, {args.encoding_duration:g} s, {args.encoding_reps} reps",
        "build": f"{args.build_sizes} bodies, {','.join(args.build_backends or installed)}",
        "robot": f"{', '.join(robot.ROBOTS)}, {args.robot_reps} reps, {','.join(args.robot_backends or installed)}",
        "startup": f"bench/scenarios/one_step.yaml on {startup.ENGINE}, {args.startup_reps} rounds",
        "seed": f"{'x'.join(map(str, args.pile))} boxes, {args.seed_duration:g} s on ode, {args.seed_reps} reps",
        "worlds": f"{args.worlds_sizes} box drops on mujoco_warp (cpu), {args.worlds_steps} steps",
    }
    results = Results(command=shlex.join(["python", "-m", "bench", *(argv if argv is not None else sys.argv[1:])]),
                      sizes={k: v for k, v in sizes.items() if k in args.sections})  # fmt: skip
    results.load = (os.getloadavg()[0], 0.0)
    results.wrapper_us = wrapper_cost() * 1e6
    notes: list[str] = []
    if "overhead" in args.sections and backends:
        log(f"overhead: {sizes['overhead']}")
        results.overhead = overhead.run(backends, tuple(args.pile), args.duration, args.reps, log)
    if "scaling" in args.sections:
        log(f"scaling: {sizes['scaling']}")
        section = time.perf_counter()
        chosen = [b for b in args.scaling_backends if b in installed]
        results.scaling, results.scaling_limits = scaling.run(chosen, args.scaling_sizes, args.scaling_duration, log)
        results.section_seconds["scaling"] = time.perf_counter() - section
    if "memory" in args.sections:
        log(f"memory: {sizes['memory']}")
        results.memory = memory.run([b for b in args.memory_backends if b in installed], args.memory_durations,
                                    tuple(args.memory_pile), log)  # fmt: skip
    if "batch" in args.sections:
        files = batch.default_files()
        if args.quick:
            files = files[:3]
        log(f"batch: {sizes['batch']}, {len(files)} files")
        results.batch = batch.run(files, args.batch_backend, args.batch_jobs, args.batch_reps, log)
    if "encoding" in args.sections:
        chosen = [b for b in (args.encoding_backends or piled) if b in installed]
        log(f"encoding: {sizes['encoding']}, {','.join(chosen)}")
        results.encoding = encoding.run(chosen, tuple(args.pile), args.encoding_duration,
                                        args.encoding_reps, log)  # fmt: skip
    if "build" in args.sections:
        log(f"build: {sizes['build']}")
        chosen = [b for b in (args.build_backends or installed) if b in installed]
        results.build = build.run(chosen, args.build_sizes, log)
    if "robot" in args.sections:
        log(f"robot: {sizes['robot']}")
        chosen = [b for b in (args.robot_backends or installed) if b in installed]
        results.robot = robot.run(chosen, args.robot_reps, log)
    if "seed" in args.sections and is_installed(seed_loop.ENGINE):
        log(f"seed: {sizes['seed']}")
        results.seed = seed_loop.run(tuple(args.pile), args.seed_duration, args.seed_reps, log)
    if "startup" in args.sections:
        log(f"startup: {sizes['startup']}")
        results.startup = startup.run(args.startup_reps, log)
    if "worlds" in args.sections and is_installed(world_batch.ENGINE):
        log(f"worlds: {sizes['worlds']}")
        results.worlds = world_batch.run(args.worlds_sizes, "cpu", args.worlds_steps, args.worlds_warmup, log)
    if "ray" in args.sections and not args.quick:  # CI runs the test itself (make test); --quick skips it
        log(f"ray: {ray_cluster.TEST}")
        results.ray = ray_cluster.run(log)
    results.load = (results.load[0], os.getloadavg()[0])
    results.wall_seconds = time.perf_counter() - started
    if args.quick:
        notes.append("`--quick`: sizes too small for the targets; this run only checks the machinery")
    text = append_notes(render(results), notes)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    log(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
