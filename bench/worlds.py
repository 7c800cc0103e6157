"""Benchmark 12: batched worlds. N box drops as the worlds of one mujoco_warp batch (backends/mujoco_warp/_batch.py),
world-steps per second against N (issue 33: rising with the batch size on CPU; docs/batch.md).

The worlds are a 0.2 m box dropped on the ground plane, the variants cycling over mass (density 500 / 1000 /
2000), start height (0.5 / 0.75 / 1.0 m) and bounce (0 / 0.3 / 0.6), dt 0.01. After ``warmup`` steps (the first
one compiles Warp's kernels, or loads them from its cache; by then most boxes have landed, so the timed steps have
contacts), ``steps`` steps are timed three ways, in interleaved rounds, as CPU time on Warp's CPU device (its
kernels run in this process) and wall time on a GPU:

* **engine**: ``mujoco_warp.step`` on the batch's device model alone (no copies: MJWarp's own figure);
* **batch**: ``step_all`` and every view's ``step()`` (the batch's copies host <-> device included);
* **batch+reads**: that and every view's ``body_states()`` each step, as the runner reads a world.

``python -m bench.worlds --device cuda --worlds 1,64,1024,8192`` (or ``python bench/gpu_batch.py``) runs it on a
GPU; ``python -m bench --sections worlds`` on CPU with 1, 64 and 256 worlds.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from backends.types import BodySpec as Body
from backends.types import CompiledWorld, Motion, Shape, ShapeKind, Surface

#: the one engine this benchmark is about (its batch: backends/mujoco_warp/_batch.py)
ENGINE = "mujoco_warp"
DENSITIES = (500.0, 1000.0, 2000.0)
HEIGHTS = (0.5, 0.75, 1.0)
BOUNCES = (0.0, 0.3, 0.6)
SIZE = 0.2
DT = 0.01
#: the timed steps are taken in this many interleaved rounds of engine / batch / batch+reads
ROUNDS = 4
#: issue 33: on CPU the world-steps per second rise with the batch size over these sizes
CPU_SIZES = (1, 64, 256)
GPU_SIZES = (1, 64, 1024, 8192)
#: what results.md says of the GPU rows until a machine with a GPU runs bench/gpu_batch.py
GPU_NOTE = "GPU (`python bench/gpu_batch.py`: cuda, 1, 64, 1,024 and 8,192 worlds): not measured: no GPU in this task."


def box_drop(k: int) -> CompiledWorld:
    """Variant ``k`` of the box drop (mass x start height x bounce, cycling)."""
    density = DENSITIES[k % 3]
    z0 = HEIGHTS[(k // 3) % 3]
    bounce = BOUNCES[(k // 9) % 3]
    mass = density * SIZE**3
    inertia = mass * SIZE * SIZE / 6.0
    zero = (0.0, 0.0, 0.0)
    ground = Body("ground", Motion.STATIC, Shape(ShapeKind.PLANE), 0.0, zero, zero, (1.0, 0.0, 0.0, 0.0), zero, zero)
    box = Body("box", Motion.DYNAMIC, Shape(ShapeKind.BOX, size=(SIZE, SIZE, SIZE)), mass, (inertia,) * 3,
               (0.0, 0.0, z0), (1.0, 0.0, 0.0, 0.0), zero, zero)  # fmt: skip
    return CompiledWorld(name="box-drop", gravity=(0.0, 0.0, -9.81), dt=DT, substeps=1, duration=2.0,
                         bodies=(ground, box), joints=(), default_surface=Surface(bounce=bounce, mu=1.0),
                         pair_surfaces=(), backend_options={ENGINE: {"device": "cpu"}})  # fmt: skip


@dataclass(frozen=True)
class WorldsFigures:
    worlds: int
    device: str
    build_s: float  # the batch's constructor (the worlds' MuJoCo models, the comparison, the device copy)
    first_step_s: float  # the first step_all: Warp's kernels compiled or loaded from its cache
    steps: int
    engine_s: float  # mujoco_warp.step alone, the timed steps
    batch_s: float  # step_all + views' step()
    reads_s: float  # the same + every view's body_states()

    def rate(self, seconds: float) -> float:
        """World-steps per second."""
        return self.worlds * self.steps / seconds if seconds > 0 else float("nan")


def measure(n: int, device: str, steps: int, warmup: int) -> WorldsFigures:
    from dataclasses import replace

    from backends.registry import get_backend

    backend = get_backend(ENGINE)
    batch_cls = backend.world_batch()
    assert batch_cls is not None  # noqa: S101 - the registry's mujoco_warp batches
    worlds = [replace(box_drop(k), backend_options={ENGINE: {"device": device}}) for k in range(n)]
    options = backend.Options.parse(worlds[0].options_for(backend.name), backend.name)
    backend.check_world(worlds[0], options)  # a CUDA device Warp does not see: refused by name (UnsupportedFeature)
    on = [True] * n
    started = time.perf_counter()
    batch = batch_cls(worlds)
    build = time.perf_counter() - started
    try:
        views = batch.views

        def one_step(reads: bool) -> None:
            batch.step_all(on)
            for v in views:
                v.step()
                if reads:
                    v.body_states()

        started = time.perf_counter()
        one_step(False)
        first = time.perf_counter() - started
        for _ in range(warmup - 1):
            one_step(False)
        clock = _clock(device)
        totals = [0.0, 0.0, 0.0]  # engine, batch, batch+reads: interleaved rounds, summed
        for _ in range(ROUNDS):
            part = steps // ROUNDS
            totals[0] += _engine_alone(batch, part, clock)
            for k, reads in ((1, False), (2, True)):
                started = clock()
                for _ in range(part):
                    one_step(reads)
                totals[k] += clock() - started
    finally:
        batch.close()
    done = ROUNDS * (steps // ROUNDS)
    return WorldsFigures(n, device, build, first, done, totals[0], totals[1], totals[2])


def _clock(device: str) -> Callable[[], float]:
    """CPU time on Warp's CPU device (its kernels run in this process, on one core: other programs' load on a
    shared machine does not lengthen it), wall time on a GPU (the host waits for the device)."""
    return time.process_time if device == "cpu" else time.perf_counter


def _engine_alone(batch: object, steps: int, clock: Callable[[], float]) -> float:
    """MJWarp's step on the batch's device model, nothing else (the engine's own throughput)."""
    import mujoco_warp as mjw
    import warp as wp

    model, data = batch._wm, batch._wd  # type: ignore[attr-defined]  # noqa: SLF001 - the bench reads the device
    wp.synchronize()
    started = clock()
    for _ in range(steps):
        mjw.step(model, data)
    wp.synchronize()
    return clock() - started


def run(sizes: Sequence[int], device: str, steps: int, warmup: int, log: Callable[[str], None]) -> list[WorldsFigures]:
    out = []
    for n in sizes:
        fig = measure(n, device, steps, warmup)
        rate, engine = fig.rate(fig.batch_s), fig.rate(fig.engine_s)
        log(f"worlds: {n} on {device}: {rate:,.0f} world-steps/s (engine {engine:,.0f})")
        out.append(fig)
    return out


def rising(figs: Sequence[WorldsFigures]) -> bool:
    rates = [f.rate(f.batch_s) for f in sorted(figs, key=lambda f: f.worlds)]
    return all(b > a for a, b in zip(rates, rates[1:], strict=False))


def target_rows(figs: Sequence[WorldsFigures]) -> list[tuple[str, str, bool, str]]:
    cpu = [f for f in figs if f.device == "cpu"]
    if len(cpu) < 2:
        return []
    shown = " -> ".join(f"{f.rate(f.batch_s):,.0f}" for f in sorted(cpu, key=lambda f: f.worlds))
    sizes = " -> ".join(str(f.worlds) for f in sorted(cpu, key=lambda f: f.worlds))
    return [(f"batched world-steps/s rise with the batch size on CPU ({sizes} worlds, mujoco_warp)", shown,
             rising(cpu), "section 12: the engine's own step and the batch's copies")]  # fmt: skip


def render(figs: Sequence[WorldsFigures], gpu_note: str = "") -> list[str]:
    if not figs:
        return []
    steps = figs[0].steps
    out = [
        "## 12. Batched worlds: box drops as the worlds of one mujoco_warp batch",
        "",
        f"bench/worlds.py: N variants of a 0.2 m box drop (mass x start height x bounce), dt {DT:g}, {steps} timed "
        f"steps after the warm-up in {ROUNDS} interleaved rounds; world-steps per second = worlds x steps / seconds "
        "(CPU time of the process on Warp's CPU device, wall time on a GPU). *engine*: `mujoco_warp.step` "
        "alone on the batch's device model; *batch*: `step_all` and each view's `step()`; *batch+reads*: and each "
        "view's `body_states()` (what the runner reads). Warp's CPU device runs its kernels on one core.",
        "",
        "| device | worlds | build (s) | first step (s) | engine world-steps/s | batch world-steps/s | "
        "batch+reads world-steps/s |",
        "|---|---|---|---|---|---|---|",
    ]
    for f in figs:
        out.append(f"| {f.device} | {f.worlds:,} | {f.build_s:.2f} | {f.first_step_s:.2f} | "
                   f"{f.rate(f.engine_s):,.0f} | {f.rate(f.batch_s):,.0f} | {f.rate(f.reads_s):,.0f} |")  # fmt: skip
    if gpu_note:
        out += ["", gpu_note]
    return [*out, ""]


def main(argv: list[str] | None = None, device: str = "cpu", sizes: Sequence[int] = CPU_SIZES) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.worlds", description=__doc__.split("\n\n")[0])
    p.add_argument("--device", default=device, help="Warp device: cpu, cuda, cuda:N")
    p.add_argument("--worlds", default=",".join(map(str, sizes)), help="batch sizes, comma-separated")
    p.add_argument("--steps", type=int, default=100, help="timed steps per size")
    p.add_argument("--warmup", type=int, default=50, help="steps before timing (the first compiles the kernels)")
    p.add_argument("--out", type=Path, default=None, help="also write the table (markdown) to this file")
    a = p.parse_args(argv)
    started = time.perf_counter()

    def log(text: str) -> None:
        print(f"[{time.perf_counter() - started:7.1f}s] {text}", flush=True)

    from backends.errors import BackendError

    try:
        figs = run([int(x) for x in a.worlds.split(",") if x.strip()], a.device, a.steps, a.warmup, log)
    except BackendError as exc:  # the device refused (no CUDA device), an option refused: said, not a traceback
        print(f"error: {exc}", file=sys.stderr)
        return 2
    text = "\n".join(render(figs)) + f"\nload average {os.getloadavg()[0]:.1f}, {os.cpu_count()} cores\n"
    print(text)
    if a.out is not None:
        a.out.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
