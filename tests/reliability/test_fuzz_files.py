"""Fuzzing the input files beside scenarios (issue 31, item 8): model files, WAVs, golden files, traces.

Each case runs in this process, through the functions the commands call (the CLI's exit code is
:func:`runner.exec.exits.classify` of what they raise), and must end in success or a refusal that the CLI
turns into exit 2 (or 74) with a located message, never exit 70; no case may take more than 20 s nor add
more than 500 MB to the process at its peak (VmHWM reset before each case, tests/reliability/memory.py):

* a mutated URDF or MJCF model (tests/reliability/file_mutations.py) is loaded and compiled as a robot of
  a scenario (`validate`): refused at the model file's (or the scenario's) line;
* a mutated WAV is a scenario's sound (`validate`), and is decoded and mixed as `report` and `compare` do
  from a trace's attachment;
* a mutated golden file is read and compared with the recording it came from, as `check` does: refused at
  the golden file's line (or, for a header key it lacks, naming the file);
* a damaged trace is read with and without recovery and summarised as `inspect` does, and one case in
  25 is made into a report as `report` does: refused naming the trace ("not a physics-scenarios trace",
  "damaged at byte N").

One case in ``FUZZ_COMMAND_EVERY`` (default 100; the first included) of the model files, WAVs and traces is
also given to the command in a subprocess (`validate`, `inspect` with and without `--recover`:
tests/reliability/sampled.py): exit code, traceback, location, time, and the peak memory of the command and
its workers under the worker's memory ceiling (runner/exec/memory.py). A golden file is only read by
`check`, which runs a scenario first: its cases stay in this process.

``FUZZ_FILES`` cases of each kind (50 in `make test`; 5,000 in `make fuzz`: 20,000 in all).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType

import pytest
from hypothesis import given
from hypothesis import strategies as st

from reports.audio import decode_wav, mix_sounds
from reports.build import ReportError, write_report
from reports.inspect import summary_text
from reports.trace_reader import SoundRecord, read_trace
from runner.ci.golden import Tolerances, dumps
from runner.ci.golden_compare import compare
from runner.ci.golden_read import loads, read_golden
from runner.ci.regression import comparison_lines
from runner.compile.program import build_program
from runner.errors import ExitCode
from runner.exec.exits import classify
from runner.language.load import load_scenario

from .conftest import STATS, count, fuzz_settings
from .file_mutations import Mutated, golden_text, model_text, trace_bytes, wav
from .hostile import ROOT
from .memory import peak_since, start_window
from .sampled import due, through_command

FUZZ_FILES = int(os.environ.get("FUZZ_FILES", "50"))
HANG_SECONDS = 20.0
PEAK_MB = 500
PYBULLET_DATA = Path(__import__("pybullet_data").getDataPath())
MODELS = {"pendulum5.urdf": ROOT / "scenarios" / "robots" / "pendulum5.urdf",
          "cartpole.urdf": PYBULLET_DATA / "cartpole.urdf",
          "hello_mjcf.xml": PYBULLET_DATA / "mjcf" / "hello_mjcf.xml",
          "inverted_pendulum.xml": PYBULLET_DATA / "mjcf" / "inverted_pendulum.xml",
          "ant.xml": PYBULLET_DATA / "mjcf" / "ant.xml"}  # fmt: skip
SEEDS = {name: path.read_text() for name, path in MODELS.items()}
ROBOT = """\
schema_version: 1
scenario: fuzzed
world: {{dt: 0.01, duration: 0.1}}
bodies:
  ground: {{plane: {{}}, motion: static}}
robots:
  r: {{{kind}: {file}}}
"""
SOUND = """\
schema_version: 1
scenario: fuzzed
world: {dt: 0.01, duration: 0.1}
sounds: {s: fuzzed.wav}
bodies:
  ball: {sphere: 0.1, mass: 1, pos: [0, 0, 1]}
inputs: [{at: 0.02, event: go}]
on:
  go: [{play_sound: s}]
"""
TIMES: dict[str, list[float]] = {}
PEAKS: dict[str, list[float]] = {}


class Hang(BaseException):
    """Not an Exception: no ``except Exception`` of the code under test may take it for bad input."""


def _alarm(signum: int, frame: FrameType | None) -> None:
    raise Hang(f"a case took more than {HANG_SECONDS:g} s")


def bounded(kind: str, how: str, work: Callable[[], str]) -> None:
    """Run one case under the time and memory bounds; count its outcome."""
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, HANG_SECONDS)
    start = time.perf_counter()
    held = start_window()
    try:
        outcome = work()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    TIMES.setdefault(kind, []).append(time.perf_counter() - start)
    peak = peak_since(held)
    PEAKS.setdefault(kind, []).append(peak)
    assert peak < PEAK_MB, f"the case added {peak:.0f} MB at its peak: {how}"
    count(f"fuzzed {kind}", outcome)
    times, peaks = TIMES[kind], PEAKS[kind]
    STATS[f"fuzzed {kind} timing"] = Counter()
    STATS[f"fuzzed {kind} timing"][f"mean {sum(times) / len(times) * 1000:.1f} ms, slowest {max(times):.2f} s, "
                                     f"largest peak added {max(peaks):.0f} MB"] = len(times)  # fmt: skip


#: the cases that ended in exit 70, by kind: every one is listed by the last test (none may be left), so that
#: a long run names every kind of crash it met rather than stopping at the first
CRASHES: dict[str, list[str]] = {}


def crashed(kind: str, exc: BaseException, how: str) -> str:
    where = next((f"{f.filename.rsplit('/', 1)[-1]}:{f.lineno}" for f in reversed(_frames(exc))
                  if "/tests/" not in f.filename and "site-packages" not in f.filename), "?")  # fmt: skip
    CRASHES.setdefault(kind, []).append(f"{type(exc).__name__} at {where}: {str(exc)[:120]} <- {how}")
    return "exit 70"


def _frames(exc: BaseException) -> list[traceback.FrameSummary]:
    return list(traceback.extract_tb(exc.__traceback__))


def refused(exc: BaseException, *places: Path, how: str, kind: str = "") -> str:
    """``exc`` as the CLI reports it: never exit 70 (recorded for :func:`test_no_case_ended_in_exit_70`
    where ``kind`` is given, else failed at once); an exit 2 names one of ``places`` with a line."""
    found = classify(exc)
    if kind and found.code == ExitCode.INTERNAL_ERROR:
        return crashed(kind, exc, how)
    assert found.code != ExitCode.INTERNAL_ERROR, f"exit 70 ({found.message[:300]}) for: {how}"
    if found.code == ExitCode.BAD_INPUT:
        located = any(re.search(rf"{re.escape(str(p))}:\d+", found.message) for p in places)
        assert located, f"an exit-2 message without file:line ({found.message[:300]}) for: {how}"
    return f"exit {int(found.code)}"


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("files")


# ---- model files ----------------------------------------------------------------------------------------
@fuzz_settings(FUZZ_FILES)
@given(data=st.data(), seed=st.sampled_from(sorted(SEEDS)))
def test_a_mutated_model_file_loads_or_is_refused_at_its_line(folder: Path, data: st.DataObject, seed: str) -> None:
    mutated: Mutated = data.draw(model_text(SEEDS[seed]))
    model = folder / seed
    scenario = folder / "robot.yaml"

    def work() -> str:
        model.write_bytes(mutated.data)
        scenario.write_text(ROBOT.format(kind="urdf" if seed.endswith(".urdf") else "mjcf", file=seed))
        try:
            build_program(load_scenario(scenario))
        except Exception as exc:  # noqa: BLE001 - classified as the CLI does
            return refused(exc, scenario, model, how=f"{seed}: {mutated.how}", kind="model files")
        return "exit 0"

    bounded("model files", f"{seed}: {mutated.how}", work)
    if due("model files"):
        through_command("model files", ["validate", str(scenario)], scenario, model, how=f"{seed}: {mutated.how}")


# ---- WAV files ------------------------------------------------------------------------------------------
@fuzz_settings(FUZZ_FILES)
@given(mutated=wav())
def test_a_mutated_wav_is_refused_at_the_scenario_or_mixed_without_error(folder: Path, mutated: Mutated) -> None:
    scenario = folder / "sound.yaml"

    def work() -> str:
        (folder / "fuzzed.wav").write_bytes(mutated.data)
        scenario.write_text(SOUND)
        try:
            build_program(load_scenario(scenario))
            outcome = "exit 0"
        except Exception as exc:  # noqa: BLE001
            outcome = refused(exc, scenario, how=mutated.how)
        try:  # as a trace's attachment: `report` and `compare` skip what they cannot decode
            samples = decode_wav(mutated.data)
        except ValueError:
            return outcome + ", not mixed"
        mix_sounds([SoundRecord(0.1, "s", "start", 0.0, 1.0)], {"s": samples}, 1.0)
        return outcome + ", mixed"

    bounded("WAV files", mutated.how, work)
    if due("WAV files"):
        through_command("WAV files", ["validate", str(scenario)], scenario, how=mutated.how)


# ---- golden files ---------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def golden_seed() -> str:
    from tests.ci.test_golden_format import recording

    return dumps(recording())


@fuzz_settings(FUZZ_FILES)
@given(data=st.data())
def test_a_mutated_golden_file_is_compared_or_refused_at_its_line(folder: Path, golden_seed: str,
                                                                  data: st.DataObject) -> None:  # fmt: skip
    mutated: Mutated = data.draw(golden_text(golden_seed))
    path = folder / "fuzzed.golden"
    original = loads(golden_seed)

    def work() -> str:
        path.write_bytes(mutated.data)
        try:
            rec = read_golden(path)
        except Exception as exc:  # noqa: BLE001
            found = classify(exc)
            if "not a baseline file" in found.message:  # a header key missing: no line to point at
                assert found.code == ExitCode.BAD_INPUT and found.message.startswith(f"{path}: "), found.message
                return "exit 2 (the file lacks a header key)"
            return refused(exc, path, how=mutated.how)
        try:
            comparison = compare(rec, original, Tolerances(rec.tolerances))
            comparison_lines(comparison)
        except Exception as exc:  # noqa: BLE001
            return refused(exc, path, how=mutated.how)
        return "matches" if comparison.ok else "diverges"

    bounded("golden files", mutated.how, work)


# ---- traces ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def trace_seed(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    """A trace of factory_intervals.yaml (sounds, events, intervals) on the fake backend."""
    out = tmp_path_factory.mktemp("seed")
    done = subprocess.run([sys.executable, "-m", "runner", "run", str(ROOT / "scenarios" / "factory_intervals.yaml"),
                           "--backend", "fake", "--out", str(out)], capture_output=True, text=True, timeout=300)
    (trace,) = out.glob("*.mcap")
    assert done.returncode in (0, 1), done.stderr
    return trace.read_bytes()


@pytest.fixture(scope="module")
def report_runtime() -> None:
    """The report's embedded chart runtime (vl-convert's JavaScript bundle), built once per process whatever the
    trace: 5-25 s here under load, a cost of the first report, not of a case (the hang bound is per case)."""
    from reports.charts import render

    render.runtime_gzip_base64()


@fuzz_settings(FUZZ_FILES)
@given(data=st.data(), report=st.integers(0, 24))
def test_a_damaged_trace_is_read_recovered_or_refused_naming_it(folder: Path, trace_seed: bytes, data: st.DataObject,
                                                               report: int, report_runtime: None) -> None:  # fmt: skip
    mutated: Mutated = data.draw(trace_bytes(trace_seed))
    path = folder / "fuzzed.mcap"

    def work() -> str:
        path.write_bytes(mutated.data)
        outcomes = []
        for recover in (False, True):
            try:
                trace = read_trace(path, recover=recover)
                summary_text(trace)
                outcomes.append("read")
            except Exception as exc:  # noqa: BLE001
                found = classify(exc)
                assert found.code != ExitCode.INTERNAL_ERROR, f"exit 70 ({found.message[:300]}) for: {mutated.how}"
                assert str(path) in found.message, f"a refusal not naming the trace: {found.message[:300]}"
                outcomes.append(f"exit {int(found.code)}")
        if report == 0 and outcomes[1] == "read":
            out = folder / "report"
            shutil.rmtree(out, ignore_errors=True)
            try:
                write_report([path], out)
                outcomes.append("reported")
            except ReportError:  # `report` prints it and exits 2
                outcomes.append("report refused")
            except Exception as exc:  # noqa: BLE001
                found = classify(exc)
                assert found.code != ExitCode.INTERNAL_ERROR, f"exit 70 ({found.message[:300]}) for: {mutated.how}"
                outcomes.append("report refused")
        return ", ".join(outcomes)

    bounded("traces", mutated.how, work)
    if due("traces"):
        for args in (["inspect", str(path)], ["inspect", "--recover", str(path)]):
            through_command("traces", args, path, how=mutated.how, lines=False)


def test_no_case_ended_in_exit_70() -> None:
    """Every crash the model-file fuzzing met, one line each with where it was raised and the mutation."""
    found = [f"{kind}: {line}" for kind, lines in CRASHES.items() for line in lines]
    assert not found, f"{len(found)} cases ended in exit 70:\n" + "\n".join(sorted(set(found))[:60])


def test_the_bomb_is_what_it_says() -> None:
    """The crafted chunk inflates to 1 GiB: a reader that trusted the data would be over its ceiling."""
    from .file_mutations import _bomb

    assert len(_bomb()) < 2 * 1024 * 1024


@pytest.fixture(autouse=True)
def _no_stray_alarm() -> Iterator[None]:
    yield
    signal.setitimer(signal.ITIMER_REAL, 0)
