"""Structured fuzzing of the loader: grammar-aware mutants of the valid scenarios (tests/reliability/grammar.py).

The contract is the loader fuzzing's (test_fuzz_loader.py): load (one variant, every variant, or a missing
one, with the mutant's `--set` items) and compile either succeed, giving a world an engine can be built from
whose trace file names are valid on every path, or raise ScenarioValidationError whose every issue is located
(file:line:column in the file, or the `--set` argument). Beyond it: no case may take more than 20 s (a
reader blocked on a FIFO, a blow-up of memory or time), and no case adds more than 500 MB to the process at its
peak (tests/reliability/memory.py: VmHWM, reset before each case).
One loaded mutant in ``FUZZ_COMMAND_EVERY`` (default 100) and one refused mutant in as many also go through
`scenario run --backend fake --no-trace --timeout 20` in a subprocess (tests/reliability/sampled.py): never
exit 70 nor a traceback, an exit 2 located in the file, the command done within its budget (plus the grace
before SIGKILL and the interpreter's start), the command's and its worker's peak memory under the worker's
memory ceiling (runner/exec/memory.py).
`FUZZ_STRUCTURED` sets the number of mutants (200 in `make test`, 20,000 in `make fuzz`).
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from types import FrameType

import pytest
from hypothesis import given
from hypothesis import strategies as st

from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import parse_overrides
from runner.sim.run import trace_path
from tests.engines import ENGINES

from .conftest import FUZZ_STRUCTURED, STATS, count, fuzz_settings
from .grammar import Mutant, mutants
from .hostile import ROOT, Case
from .memory import peak_since, start_window
from .sampled import due, through_command
from .test_fuzz_loader import assert_finite_model, assert_located, assert_sane, cases_for, line_count

HANG_SECONDS = 20.0
RUN_BUDGET = 20.0  # --timeout of the mutants run through the command
PEAK_MB = 500
NAME_MAX = 255  # bytes in a file name (Linux, macOS, Windows)
LONGEST = ".cost.json.partial"  # the longest suffix a run's files get beside `<scenario>__<variant>__<backend>`
TIMES: list[float] = []
PEAKS: list[float] = []
SLOWEST: list[str] = [""]


class Hang(Exception):
    pass


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A scenario folder with the repository's sounds, a FIFO and a socket (a sound may point at them)."""
    path = tmp_path_factory.mktemp("structured")
    shutil.copytree(ROOT / "scenarios" / "sounds", path / "sounds")
    os.mkfifo(path / "pipe.wav")
    server = socket.socket(socket.AF_UNIX)
    server.bind(str(path / "socket.wav"))
    yield path
    server.close()


def _alarm(signum: int, frame: FrameType | None) -> None:
    raise Hang(f"a case took more than {HANG_SECONDS:g} s")


def check_mutant(path: Path, mutant: Mutant, pick: int) -> str:
    path.write_bytes(mutant.data)
    case = Case(mutant.seed, mutant.data, mutant.how, mutant.variants)
    try:
        loaded = cases_for(path, case, pick, parse_overrides(list(mutant.overrides)))
    except ScenarioValidationError as exc:
        assert_located(exc, path, line_count(mutant.data))
        return "refused"
    for one in loaded:
        assert_finite_model(one)
        try:
            program = build_program(one)
        except ScenarioValidationError as exc:
            assert_located(exc, path, line_count(mutant.data))
            return "refused when compiled"
        assert_sane(program)
        for backend in ENGINES:
            name = trace_path(Path("."), one, backend).name.removesuffix(".mcap") + LONGEST
            assert len(name.encode()) <= NAME_MAX, f"a trace file name of {len(name.encode())} bytes: {name[:80]}..."
    return "loaded"


@fuzz_settings(FUZZ_STRUCTURED)
@given(mutant=mutants(), pick=st.integers(0, 99))
def test_every_structured_mutant_loads_or_is_refused_with_located_issues(
    folder: Path, mutant: Mutant, pick: int
) -> None:
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, HANG_SECONDS)
    start = time.perf_counter()
    held = start_window()
    try:
        outcome = check_mutant(folder / "case.yaml", mutant, pick)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    TIMES.append(time.perf_counter() - start)
    peak = peak_since(held)
    PEAKS.append(peak)
    assert peak < PEAK_MB, f"the case added {peak:.0f} MB at its peak: {mutant.how}"
    count("structured mutants", outcome)
    for how in mutant.how.split("; "):
        count("structured mutations", how.split(" ", 1)[0])
    if TIMES[-1] >= max(TIMES):
        SLOWEST[:] = [mutant.how]
    summary = (f"mean {sum(TIMES) / len(TIMES) * 1000:.1f} ms, slowest {max(TIMES):.2f} s ({SLOWEST[0][:60]}), "
               f"largest peak added by a case {max(PEAKS):.0f} MB")  # fmt: skip
    STATS["structured timing"] = Counter({summary: len(TIMES)})
    kind = "structured mutants loaded" if outcome == "loaded" else "structured mutants refused"
    if due(kind):  # run as a user does, on the fake backend, within a budget of RUN_BUDGET s
        path = folder / "case.yaml"
        through_command(kind, ["run", str(path), "--backend", "fake", "--no-trace", "--timeout",
                                               f"{RUN_BUDGET:g}"], path, how=mutant.how, budget=RUN_BUDGET)  # fmt: skip
