"""Benchmark 4: peak RSS of a whole run (trace on) for a short and a long simulated time.

Each run is a child process (``python -m bench.memory <backend> <duration> <nx> <ny> <nz>``) that
prints its peak resident set size as JSON, so runs do not share a heap. The peak is ``VmHWM`` from
/proc/self/status (reset by exec), not ``ru_maxrss``, which Linux carries over from the parent process.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class MemoryFigures:
    backend: str
    bodies: int
    duration: float
    steps: int
    peak_kb: int
    trace_bytes: int


def measure(backend: str, duration: float, counts: tuple[int, int, int]) -> MemoryFigures:
    cmd = [sys.executable, "-m", "bench.memory", backend, repr(duration), *map(str, counts)]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=Path(__file__).parent.parent)
    if done.returncode != 0:
        raise RuntimeError(f"memory child failed ({done.returncode}): {done.stderr[-2000:]}")
    data = json.loads(done.stdout.strip().splitlines()[-1])
    return MemoryFigures(backend, counts[0] * counts[1] * counts[2], duration, data["steps"], data["peak_kb"],
                         data["trace_bytes"])  # fmt: skip


def run(
    backends: Sequence[str],
    durations: Sequence[float],
    counts: tuple[int, int, int],
    log: Callable[[str], None] = print,
) -> list[MemoryFigures]:
    out = []
    for backend in backends:
        for duration in durations:
            fig = measure(backend, duration, counts)
            out.append(fig)
            log(f"  memory {backend} {duration:g} s: peak {fig.peak_kb / 1024:.1f} MiB, {fig.steps} steps")
    return out


def _child(argv: Sequence[str]) -> int:
    from runner.sim.run import run_loaded

    from .measure import pile

    backend, duration = argv[0], float(argv[1])
    counts = (int(argv[2]), int(argv[3]), int(argv[4]))
    with tempfile.TemporaryDirectory(prefix="bench-memory-") as tmp:
        result = run_loaded(pile(counts, duration), backend, Path(tmp))
        size = Path(result.trace).stat().st_size if result.trace else 0
    peak = _peak_kib()
    print(json.dumps({"steps": result.steps, "peak_kb": peak, "trace_bytes": size}))
    return 0


def _peak_kib() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    except OSError:
        pass
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)  # KiB on Linux, bytes on macOS


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1:]))
