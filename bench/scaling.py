"""Benchmark 2: time per step for the engine and for the runner's own part at 10, 100 and 1000 bodies.

One instrumented run per size and backend, trace on. The runner's part is everything but the engine
(step, reads, inputs, construction) and the trace writer; it must grow linearly with the body count:
the marginal cost per body from 100 to 1000 bodies should equal the one from 10 to 100.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from . import measure as m

#: Pile shapes (nx, ny, nz) for each body count: columns of at most 5 boxes.
SHAPES: dict[int, tuple[int, int, int]] = {10: (5, 2, 1), 100: (5, 5, 4), 1000: (20, 10, 5)}


def shape_for(bodies: int) -> tuple[int, int, int]:
    if bodies in SHAPES:
        return SHAPES[bodies]
    nz = 4 if bodies % 4 == 0 else 1
    return (bodies // nz, 1, nz)


@dataclass(frozen=True)
class SizeFigures:
    backend: str
    bodies: int
    timing: m.RunnerTiming

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


def run(
    backends: Sequence[str], sizes: Sequence[int], duration: float, log: Callable[[str], None] = print
) -> list[SizeFigures]:
    out: list[SizeFigures] = []
    with tempfile.TemporaryDirectory(prefix="bench-scaling-") as tmp:
        for backend in backends:
            for n in sizes:
                loaded = m.pile(shape_for(n), duration)
                timing = m.run_runner(loaded, backend, Path(tmp))
                fig = SizeFigures(backend, n, timing)
                out.append(fig)
                log(f"  scaling {backend} {n} bodies: engine {fig.engine_ms:.3f} ms/step, trace {fig.trace_ms:.3f}, "
                    f"runner {fig.runner_ms:.3f} (build {timing.engine_build:.2f} s)")  # fmt: skip
                for f in Path(tmp).iterdir():
                    f.unlink()
    return out


def marginal(figs: Sequence[SizeFigures], attr: str = "runner_ms") -> list[tuple[int, int, float]]:
    """(from, to, ms per added body per step) between successive sizes of one backend."""
    ordered = sorted(figs, key=lambda f: f.bodies)
    return [
        (a.bodies, b.bodies, (getattr(b, attr) - getattr(a, attr)) / (b.bodies - a.bodies))
        for a, b in zip(ordered, ordered[1:], strict=False)
    ]
