"""Benchmark 7: building the engine's world, time and peak memory, at 100, 1,000 and 10,000 boxes.

Each size is a child process (``python -m bench.build <backend> <nx> <ny> <nz>``) that loads the pile,
compiles it, then constructs the adapter (the engine's world, everything ``create_backend`` does) once and
prints, as JSON, the construction's wall time, the resident set size before it (``VmRSS``: the
interpreter, the engine and the compiled program) and the child's peak (``VmHWM``) after it. The peak
is the process's, so it includes the baseline; ``build_mib`` is the part the construction added. The
pile is the overhead pile's layout (columns of boxes on a plane) at the sizes in ``SHAPES``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

#: Pile shapes (nx, ny, nz) for each size: columns of 3 to 5 boxes. 10,000 is 9,999 boxes and the ground,
#: the most bodies a scenario may have (runner/language).
SHAPES: dict[int, tuple[int, int, int]] = {100: (5, 5, 4), 1000: (20, 10, 5), 10000: (101, 33, 3)}
#: A size that takes longer than this (construction included) is reported as not built.
TIMEOUT_S = 90.0
#: Issue 19's target: MuJoCo builds 1,000 bodies in at most 1 s and a peak of at most 200 MiB.
TARGET_BODIES, TARGET_SECONDS, TARGET_MIB = 1000, 1.0, 200.0


@dataclass(frozen=True)
class BuildFigures:
    backend: str
    bodies: int
    seconds: float | None  # None: the child failed or timed out (``error`` says why)
    base_kib: int  # VmRSS before the construction
    peak_kib: int  # VmHWM after it
    error: str = ""

    @property
    def peak_mib(self) -> float:
        return self.peak_kib / 1024.0

    @property
    def build_mib(self) -> float:
        return (self.peak_kib - self.base_kib) / 1024.0


def shape_for(bodies: int) -> tuple[int, int, int]:
    if bodies in SHAPES:
        return SHAPES[bodies]
    nz = 5 if bodies % 5 == 0 else 1
    return (bodies // nz, 1, nz)


def measure(backend: str, bodies: int) -> BuildFigures:
    counts = shape_for(bodies)
    cmd = [sys.executable, "-m", "bench.build", backend, *map(str, counts)]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=TIMEOUT_S,
                              cwd=Path(__file__).parent.parent)  # fmt: skip
    except subprocess.TimeoutExpired:
        return BuildFigures(backend, bodies, None, 0, 0, f"not built within {TIMEOUT_S:g} s")
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["?"])[-1]
        return BuildFigures(backend, bodies, None, 0, 0, f"exit {done.returncode}: {last[:200]}")
    data = json.loads(done.stdout.strip().splitlines()[-1])
    return BuildFigures(backend, bodies, data["seconds"], data["base_kib"], data["peak_kib"])


def run(backends: Sequence[str], sizes: Sequence[int], log: Callable[[str], None] = print) -> list[BuildFigures]:
    out = []
    for backend in backends:
        for n in sizes:
            fig = measure(backend, n)
            out.append(fig)
            if fig.seconds is None:
                log(f"  build {backend} {n} bodies: {fig.error}")
            else:
                log(f"  build {backend} {n} bodies: {fig.seconds:.3f} s, peak {fig.peak_mib:.1f} MiB "
                    f"(+{fig.build_mib:.1f} MiB)")  # fmt: skip
    return out


def targets(figs: Sequence[BuildFigures]) -> list[str]:
    """Rows of results.md's target table: the build at TARGET_BODIES, each backend measured there."""
    rows = []
    for f in figs:
        if f.bodies != TARGET_BODIES:
            continue
        if f.seconds is None:
            rows.append(f"| build, {f.backend}, {f.bodies} boxes: <= {TARGET_SECONDS:g} s and <= {TARGET_MIB:g} MiB "
                        f"| {f.error} | **not met** | |")  # fmt: skip
            continue
        ok = f.seconds <= TARGET_SECONDS and f.peak_mib <= TARGET_MIB
        rows.append(f"| build, {f.backend}, {f.bodies} boxes: <= {TARGET_SECONDS:g} s and <= {TARGET_MIB:g} MiB "
                    f"| {f.seconds:.2f} s, {f.peak_mib:.0f} MiB | {'met' if ok else '**not met**'} "
                    f"| peak of the whole process ({f.base_kib / 1024:.0f} MiB before the build) |")  # fmt: skip
    return rows


def render(figs: Sequence[BuildFigures]) -> list[str]:
    out = [
        "## 7. Build: the engine's world from the compiled pile (child process per size)",
        "",
        "| backend | size | boxes | build (s) | RSS before (MiB) | peak (MiB) | added by the build (MiB) |",
        "|---|---|---|---|---|---|---|",
    ]
    for f in figs:
        nx, ny, nz = shape_for(f.bodies)
        if f.seconds is None:
            out.append(f"| {f.backend} | {f.bodies} | {nx * ny * nz} | {f.error} | | | |")
        else:
            out.append(f"| {f.backend} | {f.bodies} | {nx * ny * nz} | {f.seconds:.3f} | {f.base_kib / 1024:.1f} "
                       f"| {f.peak_mib:.1f} | {f.build_mib:.1f} |")  # fmt: skip
    return [*out, "", "The build is the adapter's constructor (`create_backend`): for MuJoCo the MjSpec, its "
            "compilation, MjData and one mj_forward.", ""]  # fmt: skip


def _child(argv: Sequence[str]) -> int:
    from backends.registry import create_backend, get_backend

    from .measure import pile, world_of

    backend, counts = argv[0], (int(argv[1]), int(argv[2]), int(argv[3]))
    world, _ = world_of(pile(counts, 1.0))
    get_backend(backend)  # the adapter and its engine imported: not part of the build
    base = _status_kib("VmRSS")
    start = time.perf_counter()
    adapter = create_backend(backend, world)
    seconds = time.perf_counter() - start
    peak = _status_kib("VmHWM")
    adapter.close()
    print(json.dumps({"seconds": seconds, "base_kib": base, "peak_kib": peak}))
    return 0


def _status_kib(field: str) -> int:
    """A /proc/self/status figure in KiB (Linux; the benchmarks run there)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(f"{field}:"):
            return int(line.split()[1])
    raise RuntimeError(f"/proc/self/status has no {field}")


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1:]))
