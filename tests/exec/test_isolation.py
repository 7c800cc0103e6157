"""runner.exec: a case in a worker process; crashes, hangs and refusals come back as results, never take the
caller down, and leave their (partial) traces and outcome files.

Each test starts one or two worker processes (well under a second each); the hang test waits for its
4 s limit and a 1 s grace period, about 6 s in all.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from reports import outcome as oc
from reports.trace_reader import read_trace
from runner.exec.cases import Case
from runner.exec.executors import LocalExecutor
from runner.language.load import load_scenario
from runner.sim.run import run_loaded
from tests.paths import ROOT

FACTORY = ROOT / "scenarios" / "factory_physics.yaml"
CLI = [sys.executable, "-m", "runner"]
VARIANT = "door-stays-closed"
DT = 0.04


def _case(out: Path | None, backend: str = "crash", variant: str = VARIANT, budget: float | None = None,
          **crash: object) -> Case:  # fmt: skip
    overrides = tuple((f"backend_options.crash.{k}", v) for k, v in crash.items())
    return Case(str(FACTORY), variant, backend, overrides, None if out is None else str(out), budget=budget)


def test_a_completed_run_matches_an_in_process_run(tmp_path: Path) -> None:
    (isolated,) = LocalExecutor(1, isolate=True).run([_case(tmp_path / "child", "fake")])
    direct = run_loaded(load_scenario(FACTORY, VARIANT), "fake", tmp_path / "direct")
    assert isolated.result is not None and isolated.outcome_file is None
    assert isolated.status == direct.status == "failed"  # no contacts on fake: the box falls through
    assert [v.as_dict() for v in isolated.result.verdicts] == [v.as_dict() for v in direct.verdicts]
    assert isolated.result.events == direct.events
    assert isolated.trace == str(tmp_path / "child" / "factory-physics__door-stays-closed__fake.mcap")
    assert Path(isolated.trace).read_bytes() == Path(direct.trace).read_bytes()
    assert not oc.outcome_path(Path(isolated.trace)).exists()
    (untraced,) = LocalExecutor(1).run([_case(None, "fake")])
    assert untraced.trace is None and untraced.result is not None
    assert [v.as_dict() for v in untraced.result.verdicts] == [v.as_dict() for v in direct.verdicts]


@pytest.mark.parametrize("sig", ["SIGSEGV", "SIGKILL", "SIGABRT"])
def test_a_crash_is_reported_with_its_signal_and_the_partial_trace_is_kept(tmp_path: Path, sig: str) -> None:
    (run,) = LocalExecutor(1).run([_case(tmp_path, after_steps=30, signal=sig)])
    number = int(getattr(signal, sig))
    assert run.status == "crashed" and run.signal == number and run.returncode == -number
    assert run.label == f"crashed (signal {number})" and run.exit.code == 3
    assert run.trace is not None and run.trace.endswith(".mcap.partial")
    trace = read_trace(run.trace, recover=True)
    # the writer closes a chunk after the first step at or past each whole simulated second, and the
    # crash comes after step 30 (t = 1.2 s): what survives is every step up to t = 1.0 s
    assert trace.times[-1] == pytest.approx(1.0) and len(trace.times) == 26
    assert trace.status == "incomplete"
    saved = json.loads(Path(run.outcome_file or "").read_text())
    assert saved["outcome"] == "crashed" and saved["signal"] == number and saved["trace"] == Path(run.trace).name
    assert oc.read_outcome(Path(run.outcome_file or "")).label == run.label


@pytest.mark.slow
def test_a_hang_times_out_and_is_killed_after_the_grace_period(tmp_path: Path) -> None:
    """An engine call that never returns (the crash backend sleeps inside its step, with or without SIGTERM
    ignored): the time limit's SIGTERM waits for the engine to return, which it never does, so SIGKILL
    follows the grace period and the trace up to its last chunk is kept. About 5 s."""
    polite = _case(tmp_path, budget=4.0, after_steps=5, fault="hang")
    stubborn = _case(tmp_path, variant="reset-box-on-closed-door", budget=4.0, after_steps=5,
                     fault="hang-ignoring-sigterm")  # fmt: skip
    results = LocalExecutor(2, grace=1.0).run([polite, stubborn])
    for res in results:
        assert res.status == "timed-out" and res.label == "timed out" and res.exit.code == 3
        assert res.signal == signal.SIGKILL and res.trace is not None and res.trace.endswith(".partial")
        assert read_trace(res.trace, recover=True).scenario["backend"] == "crash"
        detail = oc.read_outcome(Path(res.outcome_file or "")).detail
        assert detail.startswith("no result after 4 s; stopped by signal 9")
        assert res.headline == "timed out: no result after 4 s (world.budget, or --timeout); stopped by signal 9"


def test_a_slow_run_is_stopped_by_its_budget_with_a_finished_trace(tmp_path: Path) -> None:
    """A run whose steps return but whose projected cost is over its budget stops itself at a step
    boundary (runner.sim.budget), naming the cost per step; its trace is finished. About 1.5 s: the
    watchdog trusts a projection after 1 s of stepping."""
    source = tmp_path / "slow.yaml"
    source.write_text(
        "schema_version: 1\nscenario: slow\nworld: {dt: 0.01, duration: 100000, budget: 5}\n"
        "bodies:\n  ball: {sphere: 0.1, density: 1000, pos: [0, 0, 1]}\n"
    )
    (res,) = LocalExecutor(1).run([Case(str(source), None, "fake", (), str(tmp_path / "out"), budget=5.0)])
    assert res.status == "engine-failure" and res.exit.code == 3
    assert "each step costs" in res.headline and "over the wall-clock budget of 5 s" in res.headline
    trace = read_trace(res.trace or "")
    assert trace.status == "engine-failure" and 1.0 < trace.times[-1] < 100000


def test_a_refused_case_is_an_error_with_its_class_and_message(tmp_path: Path) -> None:
    from backends.errors import UnsupportedFeature

    (run,) = LocalExecutor(1).run([_case(tmp_path, fault="explode")])
    assert run.status == "error" and isinstance(run.error, UnsupportedFeature) and run.exit.code == 2
    assert "backend_options.crash.fault" in run.headline and "explode" in run.headline
    assert run.trace is None and oc.read_outcome(Path(run.outcome_file or "")).message == str(run.error)


def test_stale_outputs_of_a_case_are_replaced(tmp_path: Path) -> None:
    (crashed,) = LocalExecutor(1).run([_case(tmp_path, after_steps=3)])
    assert crashed.status == "crashed" and crashed.outcome_file is not None and crashed.trace is not None
    (done,) = LocalExecutor(1).run([_case(tmp_path, after_steps=100000)])
    assert done.result is not None and done.trace is not None and done.trace.endswith(".mcap")
    assert not Path(crashed.outcome_file).exists() and not Path(crashed.trace).exists()


@pytest.mark.parametrize("fault", ["none", "hang"])
def test_sigterm_to_compare_stops_its_workers_and_keeps_their_traces(tmp_path: Path, fault: str) -> None:
    """`scenario compare` gets SIGTERM mid-run: its worker gets it too and finishes the trace as interrupted
    at the next step; a worker hung inside an engine call is killed after the grace period, its trace kept
    up to its last chunk. compare exits 143 either way, never after the time limit. 2 to 8 s."""
    extra = ["--set", "backend_options.crash.fault=hang", "--set", "backend_options.crash.after_steps=3"]
    if fault == "none":
        extra = ["--set", "world.duration=100000", "--set", "backend_options.crash.after_steps=100000000"]
    proc = subprocess.Popen([*CLI, "compare", str(FACTORY), "--backends", "crash", "--out", str(tmp_path), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    trace = tmp_path / "traces" / "factory-physics__door-stays-closed__crash.mcap"
    deadline = time.monotonic() + 60
    while not trace.with_name(trace.name + ".partial").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)  # well into the run (or the hang, after 3 steps)
    sent = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err
    assert time.monotonic() - sent < 15  # STOP_GRACE (10 s) at most
    if fault == "none":
        assert read_trace(trace).status == "interrupted"
    else:
        assert read_trace(trace, recover=True).status == "incomplete"
