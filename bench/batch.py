"""Benchmark 5: a batch of scenario files and variants with ``-j N`` against ``-j 1``.

Each measurement is a whole command in a child process (start-up included), as a user or CI pays it:
``scenario run FILES --all-variants -j N`` when the CLI has ``-j``, otherwise ``python -m bench.batch``
running the same cases through :class:`runner.exec.executors.LocalExecutor`, which ``run -j`` uses.
"""

from __future__ import annotations

import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).parent.parent


def default_files() -> list[Path]:
    return sorted((ROOT / "scenarios").glob("*.yaml")) + sorted((ROOT / "scenarios" / "conformance").glob("*.yaml"))


def cli_has_jobs() -> bool:
    scenario = shutil.which("scenario", path=str(Path(sys.executable).parent))
    if scenario is None:
        return False
    done = subprocess.run([scenario, "run", "--help"], capture_output=True, text=True, check=False)
    return "--jobs" in done.stdout


@dataclass
class BatchFigures:
    backend: str
    files: int
    cases: int = 0
    via: str = ""
    seconds: dict[int, list[float]] = field(default_factory=dict)  # jobs -> per repetition
    exit_codes: set[int] = field(default_factory=set)
    #: jobs -> wall seconds of a fixed pure-Python loop split over that many processes, per repetition
    ceiling: dict[int, list[float]] = field(default_factory=dict)
    #: wall seconds of `scenario validate FILES` (start-up and loading every variant: what -j cannot divide)
    serial: list[float] = field(default_factory=list)
    #: jobs -> per repetition, the cases' own wall seconds (their cost.json files): summed, and the longest
    case_sum: dict[int, list[float]] = field(default_factory=dict)
    case_max: dict[int, list[float]] = field(default_factory=dict)

    def median(self, jobs: int) -> float:
        return statistics.median(self.seconds[jobs])

    def speedup(self, jobs: int) -> float:
        return self.median(1) / self.median(jobs)

    def share_of_ceiling(self, jobs: int) -> float:
        """The speed-up over the ceiling's: 1.0 is everything the machine gives parallel work."""
        return self.speedup(jobs) / self.ceiling_speedup(jobs)

    def serial_seconds(self) -> float:
        return statistics.median(self.serial) if self.serial else float("nan")

    def contention(self, jobs: int) -> float:
        """How much longer the cases took side by side: their summed wall time at ``jobs`` over at -j 1 (1.0: a
        case runs as fast beside others as alone; NaN if not measured)."""
        if not self.case_sum.get(jobs) or not self.case_sum.get(1):
            return float("nan")
        return statistics.median(self.case_sum[jobs]) / statistics.median(self.case_sum[1])

    def ideal(self, jobs: int) -> float:
        """The -j time if the cases ran side by side as fast as alone and split perfectly, bar the longest: the
        serial part plus max(sum / jobs, longest case) of -j 1's case times (NaN if not measured)."""
        if not self.case_sum.get(1):
            return float("nan")
        work, longest = statistics.median(self.case_sum[1]), statistics.median(self.case_max[1])
        return self.serial_seconds() + max(work / jobs, longest)

    def ceiling_speedup(self, jobs: int) -> float:
        """What this machine gives perfectly parallel CPU work on ``jobs`` processes (NaN if not measured)."""
        if jobs not in self.ceiling or 1 not in self.ceiling:
            return float("nan")
        return statistics.median(self.ceiling[1]) / statistics.median(self.ceiling[jobs])


#: iterations of the calibration loop, split over the processes (about 2 s of one core)
SPIN_WORK = 24_000_000


def spin(jobs: int, work: int = SPIN_WORK) -> float:
    """Wall seconds for ``work`` iterations of a pure-Python loop split over ``jobs`` processes started
    together: perfectly parallel work with no I/O and no shared data, the machine's ceiling for ``-j``."""
    code = f"x = 0\nfor i in range({work // jobs}):\n    x += i\n"
    start = time.perf_counter()
    children = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(jobs)]
    for child in children:
        child.wait()
    return time.perf_counter() - start


def _command(files: Sequence[Path], backend: str, jobs: int, out: Path, cli: bool) -> list[str]:
    if cli:
        scenario = str(Path(sys.executable).parent / "scenario")
        return [scenario, "run", *map(str, files), "--all-variants", "-b", backend, "-q", "--out", str(out),
                "-j", str(jobs)]  # fmt: skip
    return [sys.executable, "-m", "bench.batch", backend, str(jobs), str(out), *map(str, files)]


def run(
    files: Sequence[Path], backend: str, jobs: Sequence[int], repetitions: int, log: Callable[[str], None] = print
) -> BatchFigures:
    cli = cli_has_jobs()
    fig = BatchFigures(backend, len(files), via="scenario run -j" if cli else "runner.exec.executors.LocalExecutor")
    fig.cases = _count_cases(files)
    with tempfile.TemporaryDirectory(prefix="bench-batch-") as tmp:
        for rep in range(repetitions):
            order = list(jobs) if rep % 2 == 0 else list(reversed(jobs))
            for j in order:
                out = Path(tmp, f"j{j}")
                start = time.perf_counter()
                done = subprocess.run(_command(files, backend, j, out, cli), capture_output=True, cwd=ROOT, check=False)
                fig.seconds.setdefault(j, []).append(time.perf_counter() - start)
                fig.exit_codes.add(done.returncode)
                walls = _case_walls(out)
                if walls:
                    fig.case_sum.setdefault(j, []).append(sum(walls))
                    fig.case_max.setdefault(j, []).append(max(walls))
                shutil.rmtree(out, ignore_errors=True)
                fig.ceiling.setdefault(j, []).append(spin(j))
            if cli:
                start = time.perf_counter()
                subprocess.run([str(Path(sys.executable).parent / "scenario"), "validate", *map(str, files)],
                               capture_output=True, cwd=ROOT, check=False)  # fmt: skip
                fig.serial.append(time.perf_counter() - start)
            times = ", ".join(f"-j {j} {fig.seconds[j][-1]:.2f}s (pure loop {fig.ceiling[j][-1]:.2f}s)" for j in jobs)
            log(f"  batch round {rep + 1}/{repetitions}: {times}")
    return fig


def _case_walls(out: Path) -> list[float]:
    """Each case's own wall seconds, from the cost files `scenario run` writes beside its traces."""
    walls = []
    for path in sorted(out.glob("*.cost.json")):
        try:
            walls.append(float(json.loads(path.read_text())["wall_seconds"]))
        except (OSError, ValueError, KeyError, TypeError):
            continue
    return walls


def _count_cases(files: Sequence[Path]) -> int:
    from runner.language.load import variant_names

    return sum(len(variant_names(f)) for f in files)


def _child(argv: Sequence[str]) -> int:
    """The batch without `run -j`: every variant of every file through the local executor."""
    from runner.exec.executors import Case, LocalExecutor, estimate_cost, status_code
    from runner.language.load import load_all

    backend, jobs, out = argv[0], int(argv[1]), argv[2]
    cases = [
        Case(f, None if c.variant == "base" else c.variant, backend, (), out, cost=estimate_cost(c))
        for f in argv[3:]
        for c in load_all(Path(f), None, True)
    ]
    return status_code(LocalExecutor(jobs).run(cases))


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1:]))
