"""runner.exec.isolation: one case in a child process; crashes, hangs and refusals come back as outcomes.

Each test starts one or two child processes (about 0.5 s each); the hang test waits for its 4 s limit
and a 1 s grace period, about 6 s in all.
"""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

import pytest

from reports import outcome as oc
from reports.trace_reader import read_trace
from runner.exec.isolation import COMPLETED, run_isolated, run_many
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

from .conftest import CLI, FACTORY

VARIANT = "door-stays-closed"
DT = 0.04


def _case(**crash: object):  # noqa: ANN202 - a LoadedScenario
    return load_scenario(FACTORY, VARIANT, tuple((f"backend_options.crash.{k}", v) for k, v in crash.items()))


def test_completed_run_matches_an_in_process_run(tmp_path: Path) -> None:
    case = _case()
    isolated = run_isolated(case, "fake", tmp_path / "child", timeout=120)
    direct = run_loaded(case, "fake", tmp_path / "direct")
    assert isolated.outcome == COMPLETED and isolated.result is not None and isolated.outcome_file is None
    assert isolated.result.status == direct.status == "failed"  # no contacts on fake: the box falls through
    assert [v.as_dict() for v in isolated.result.verdicts] == [v.as_dict() for v in direct.verdicts]
    assert isolated.result.events == direct.events
    assert isolated.trace == tmp_path / "child" / "factory-physics__door-stays-closed__fake.mcap"
    assert (tmp_path / "child").joinpath(isolated.trace.name).read_bytes() == Path(direct.trace).read_bytes()
    assert not oc.outcome_path(isolated.trace).exists()
    untraced = run_isolated(case, "fake", None, timeout=120)
    assert untraced.completed and untraced.trace is None and untraced.result is not None
    assert [v.as_dict() for v in untraced.result.verdicts] == [v.as_dict() for v in direct.verdicts]


@pytest.mark.parametrize("sig", ["SIGSEGV", "SIGKILL"])
def test_a_crash_is_reported_with_its_signal_and_the_partial_trace_is_kept(tmp_path: Path, sig: str) -> None:
    run = run_isolated(_case(after_steps=30, signal=sig), "crash", tmp_path, timeout=120)
    number = int(getattr(signal, sig))
    assert run.outcome == oc.CRASHED and run.signal == number and run.returncode == -number
    assert run.label == f"crashed (signal {number})"
    assert run.trace is not None and run.trace.name.endswith(".mcap.partial")
    trace = read_trace(run.trace, recover=True)
    # the writer closes a chunk after the first step at or past each whole simulated second, and the
    # crash comes after step 30 (t = 1.2 s): what survives is every step up to t = 1.0 s
    assert trace.times[-1] == pytest.approx(1.0) and len(trace.times) == 26
    assert trace.status == "incomplete"
    saved = json.loads(run.outcome_file.read_text())
    assert saved["outcome"] == "crashed" and saved["signal"] == number and saved["trace"] == run.trace.name
    assert oc.read_outcome(run.outcome_file).label == run.label


@pytest.mark.slow
def test_hangs_time_out_and_a_run_that_ignores_sigterm_is_killed(tmp_path: Path) -> None:
    """Waits for the 4 s time limit and a 1 s grace period: about 5 s."""
    polite = _case(after_steps=5, fault="hang")
    stubborn = load_scenario(
        FACTORY, "reset-box-on-closed-door",
        (("backend_options.crash.after_steps", 5), ("backend_options.crash.fault", "hang-ignoring-sigterm")),
    )  # fmt: skip
    first, second = run_many([(polite, "crash"), (stubborn, "crash")], tmp_path, jobs=2, timeout=4.0, grace=1.0)
    assert first.outcome == second.outcome == oc.TIMED_OUT and first.label == "timed out"
    # SIGTERM reached the sleeping child: its trace is finished and marked interrupted; the hang came
    # inside step 5, so the last recorded state is the one after step 4
    assert first.signal is None and first.trace is not None and first.trace.suffix == ".mcap"
    trace = read_trace(first.trace)
    assert trace.status == "interrupted" and trace.times[-1] == pytest.approx(4 * DT)
    # the other ignored SIGTERM and was killed after the grace period; its partial trace is kept
    assert second.signal == signal.SIGKILL and second.trace is not None and second.trace.name.endswith(".partial")
    assert read_trace(second.trace, recover=True).scenario["backend"] == "crash"
    assert oc.read_outcome(second.outcome_file).detail.startswith("no result after 4 s; stopped by signal 9")


def test_a_refused_case_is_an_error_outcome_with_the_message(tmp_path: Path) -> None:
    run = run_isolated(_case(fault="explode"), "crash", tmp_path, timeout=120)
    assert run.outcome == oc.ERROR and run.returncode == 2 and run.trace is None
    assert "backend_options.crash.fault" in run.message and "explode" in run.message
    assert oc.read_outcome(run.outcome_file).message == run.message


def test_stale_outputs_of_a_case_are_replaced(tmp_path: Path) -> None:
    crashed = run_isolated(_case(after_steps=3), "crash", tmp_path, timeout=120)
    assert crashed.outcome == oc.CRASHED and crashed.outcome_file is not None
    stale_partial = crashed.trace
    done = run_isolated(_case(after_steps=100000), "crash", tmp_path, timeout=120)
    assert done.outcome == COMPLETED and done.trace is not None and done.trace.suffix == ".mcap"
    assert not crashed.outcome_file.exists() and stale_partial is not None and not stale_partial.exists()


def test_sigterm_to_compare_stops_its_children_and_keeps_their_traces(tmp_path: Path) -> None:
    """`scenario compare` gets SIGTERM while a run hangs: the run's child is stopped (its trace finished and
    marked interrupted) and compare exits 143 at once, not after the 600 s time limit. About 3 s."""
    proc = subprocess.Popen(
        [*CLI, "compare", str(FACTORY), "--backends", "crash", "--out", str(tmp_path),
         "--set", "backend_options.crash.fault=hang", "--set", "backend_options.crash.after_steps=3"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    trace = tmp_path / "traces" / "factory-physics__door-stays-closed__crash.mcap"
    deadline = time.monotonic() + 60
    while not trace.with_name(trace.name + ".partial").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)  # the child reaches its hang after 3 steps
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err
    assert read_trace(trace).status == "interrupted"
