"""Benchmark 2: time per step for the engine, the trace and the runner's own part, memory per body and trace
bytes per body per step, from 10 to 10,000 bodies.

One instrumented run per size and backend, trace on, each in a child process (``python -m bench.scaling
BACKEND BODIES DURATION``) so that its memory is its own: the peak RSS (VmHWM) after the run against the RSS
with the engine imported gives the memory per body. Large piles run fewer steps (the simulated time is
``duration x min(1, 1000 / bodies)``, at least :data:`MIN_STEPS_BEYOND` steps) so that the whole table
stays within minutes; the figures are per step and per body. A run that needs more than :data:`CPU_LIMIT_S`
seconds of CPU (a limit the machine's load does not move) is reported as such, and that backend's larger
sizes are not tried (the limit stated in results.md); any other failure is reported as a limit too, with
its last line of error. The runner's part is everything but the engine (step,
reads, inputs, construction) and the trace writer; it must grow linearly with the body count: the marginal
cost per body from the largest sizes should not exceed the one from 10 to 100.
"""

from __future__ import annotations

import json
import math
import resource
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from . import measure as m

#: Pile shapes (nx, ny, nz) for each body count: columns of at most 5 boxes.
#: 10,000: the scenario language's limit counts the ground, so 9,999 boxes (one layer of 101 x 99, as bench/build.py).
SHAPES: dict[int, tuple[int, int, int]] = {10: (5, 2, 1), 100: (5, 5, 4), 1000: (20, 10, 5), 10000: (101, 99, 1)}
CPU_LIMIT_S = 120  # CPU seconds of one run (child process), build included: the engine's limit, whatever the load
WALL_LIMIT_S = 900.0  # and a wall-clock backstop
FULL_STEPS_UP_TO = 1000  # bodies; beyond, the simulated time shrinks in proportion
#: ... but never below this many steps: a run's fixed work (loading, compiling the assertions, the first
#: step's name maps) is O(bodies) once per run, and spread over 25 steps at 9,999 bodies it read as a per-step
#: cost (measured on MuJoCo without a trace: runner 0.92 us/body/step over 25 steps, 0.30 over 100, the
#: same as at 100 and 1,000 bodies)
MIN_STEPS_BEYOND = 100


def shape_for(bodies: int) -> tuple[int, int, int]:
    if bodies in SHAPES:
        return SHAPES[bodies]
    nz = 4 if bodies % 4 == 0 else 1
    return (bodies // nz, 1, nz)


def duration_for(bodies: int, duration: float, dt: float = 0.004) -> float:
    """The simulated time of a run: ``duration`` up to FULL_STEPS_UP_TO bodies, then shorter in proportion
    (whole steps, at least 10; beyond FULL_STEPS_UP_TO bodies at least MIN_STEPS_BEYOND)."""
    steps = max(10, math.floor(duration / dt * min(1.0, FULL_STEPS_UP_TO / bodies) + 0.5))
    if bodies > FULL_STEPS_UP_TO:
        steps = max(steps, MIN_STEPS_BEYOND)
    return steps * dt


@dataclass(frozen=True)
class SizeFigures:
    backend: str
    bodies: int
    timing: m.RunnerTiming
    base_kib: int = 0  # RSS of the child before the scenario is loaded
    peak_kib: int = 0  # VmHWM after the run
    wall_seconds: float = 0.0  # the child process, start-up included

    def per_step(self, seconds: float) -> float:
        return seconds / max(self.timing.steps, 1)

    @property
    def engine_ms(self) -> float:
        t = self.timing
        return 1e3 * self.per_step(t.engine_step + t.engine_reads + t.engine_inputs)

    @property
    def trace_ms(self) -> float:
        return 1e3 * self.per_step(self.timing.trace)

    @property
    def runner_ms(self) -> float:
        return 1e3 * self.per_step(self.timing.runner_own)

    @property
    def runner_us_per_body(self) -> float:
        return 1e3 * self.runner_ms / self.bodies

    @property
    def kib_per_body(self) -> float:
        return (self.peak_kib - self.base_kib) / self.bodies

    @property
    def trace_bytes_per_body_step(self) -> float:
        return self.timing.trace_bytes / ((self.bodies + 1) * max(self.timing.steps, 1))  # + the ground


@dataclass(frozen=True)
class Limit:
    backend: str
    bodies: int
    reason: str


def measure(backend: str, bodies: int, duration: float) -> SizeFigures | Limit:
    """One run in a child process, with its trace."""
    cmd = [sys.executable, "-m", "bench.scaling", backend, str(bodies), repr(duration_for(bodies, duration))]
    start = time.perf_counter()
    boxes = math.prod(shape_for(bodies))  # the figures and limits count the boxes actually built
    simulated = f"build and {duration_for(bodies, duration):g} s simulated"
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=WALL_LIMIT_S,
                              cwd=Path(__file__).parent.parent, preexec_fn=_limit_cpu)  # fmt: skip
    except subprocess.TimeoutExpired:
        return Limit(backend, boxes, f"not done within {WALL_LIMIT_S:g} s of wall time ({simulated})")
    wall = time.perf_counter() - start
    if done.returncode in (-signal.SIGXCPU, -signal.SIGKILL):
        return Limit(backend, boxes, f"not done within {CPU_LIMIT_S} s of CPU time ({simulated})")
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or [""])[-1]
        return Limit(backend, boxes, f"failed (exit {done.returncode}): {last}")
    data = json.loads(done.stdout.strip().splitlines()[-1])
    return SizeFigures(backend, boxes, m.RunnerTiming(**data["timing"]), data["base_kib"], data["peak_kib"], wall)


def _limit_cpu() -> None:
    """In the child, before exec: SIGXCPU after CPU_LIMIT_S seconds of CPU, SIGKILL 5 s later."""
    resource.setrlimit(resource.RLIMIT_CPU, (CPU_LIMIT_S, CPU_LIMIT_S + 5))


def run(
    backends: Sequence[str], sizes: Sequence[int], duration: float, log: Callable[[str], None] = print
) -> tuple[list[SizeFigures], list[Limit]]:
    out: list[SizeFigures] = []
    limits: list[Limit] = []
    for backend in backends:
        for n in sorted(sizes):
            fig = measure(backend, n, duration)
            if isinstance(fig, Limit):
                limits.append(fig)
                log(f"  scaling {backend} {n} bodies: {fig.reason}; larger sizes not tried")
                break
            out.append(fig)
            log(f"  scaling {backend} {n} bodies: engine {fig.engine_ms:.3f} ms/step, trace {fig.trace_ms:.3f}, "
                f"runner {fig.runner_ms:.3f}, {fig.kib_per_body:.1f} KiB/body (build {fig.timing.engine_build:.2f} s, "
                f"{fig.wall_seconds:.0f} s in all)")  # fmt: skip
    return out, limits


def marginal(figs: Sequence[SizeFigures], attr: str = "runner_ms") -> list[tuple[int, int, float]]:
    """(from, to, ms per added body per step) between successive sizes of one backend."""
    ordered = sorted(figs, key=lambda f: f.bodies)
    return [
        (a.bodies, b.bodies, (getattr(b, attr) - getattr(a, attr)) / (b.bodies - a.bodies))
        for a, b in zip(ordered, ordered[1:], strict=False)
    ]


def _child(argv: Sequence[str]) -> int:
    from .memory import _peak_kib

    backend, bodies, duration = argv[0], int(argv[1]), float(argv[2])
    m.get_backend(backend)  # the adapter and its engine imported: the base is everything but the world
    base = _rss_kib()
    loaded = m.pile(shape_for(bodies), duration)
    with tempfile.TemporaryDirectory(prefix="bench-scaling-") as tmp:
        timing = m.run_runner(loaded, backend, Path(tmp))
    print(json.dumps({"timing": asdict(timing), "base_kib": base, "peak_kib": _peak_kib()}))
    return 0


def _rss_kib() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1:]))
