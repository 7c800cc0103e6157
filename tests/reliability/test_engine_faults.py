"""Engine aborts, hangs and runaway costs (issue 15, items 10 and 12): exit 3 naming the cause on every path,
a run always interruptible, a run whose cost explodes stopped with a message naming that cost.

* An engine that kills its process (ODE's internal assertion on a 1 ug box: SIGABRT) is "crashed (signal
  6)", exit 3, with the engine's message and the trace kept as .partial, serially too (measured before:
  exit 134 unless --isolate). The other paths: tests/exec/test_exit_codes.py.
* 300 spheres in one place on PyBullet: its first step does not return for minutes (measured: over 40 s,
  not finished), ignoring signals (measured before: two SIGTERMs ignored for 15 s). The second signal ends
  the run at once; one signal ends it after the grace period; --timeout ends it as "timed out".
* 1000 spheres in one place on DART: about 0.1 s per step after a 2 s first step (measured: 2.26 s, then
  0.10, 0.09); 5000 steps would take about 8 minutes: a budget of 20 s stops it at a step boundary,
  naming the cost per step, with a finished trace.
"""

from __future__ import annotations

import signal
import time
from pathlib import Path

import pytest

from backends.registry import is_installed
from reports.trace_reader import read_trace

from .processes import start, wait_released, worker_of

TINY = """\
schema_version: 1
scenario: tiny
world: {dt: 0.01, duration: 0.5}
bodies:
  ground: {plane: {}, motion: static}
  grain: {box: [0.003, 0.003, 0.003], mass: 1e-9, pos: [0, 0, 0.1]}
"""

PILE = """\
schema_version: 1
scenario: pile
world: {{dt: 0.01, duration: {duration}{budget}}}
bodies:
  ground: {{plane: {{}}, motion: static}}
  ball: {{sphere: 0.1, density: 1000, pos: [0, 0, 1], array: {{count: {count}, spacing: [0, 0, 0]}}}}
"""


def needs(engine: str) -> None:
    if not is_installed(engine):
        pytest.skip(f"engine not installed: {engine}")


@pytest.mark.parametrize("path", [[], ["-j", "2"], ["--trace-process"]], ids=["serial", "-j 2", "--trace-process"])
def test_an_engine_abort_is_a_crash_with_its_signal_on_the_serial_path_too(tmp_path: Path, path: list[str]) -> None:
    needs("ode")
    source = tmp_path / "tiny.yaml"
    source.write_text(TINY)
    proc = start("run", str(source), "--backend", "ode", "--out", str(tmp_path), *path)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 3, out + err
    assert "Traceback" not in err and "tiny · base · ode: crashed (signal 6): ODE INTERNAL ERROR" in out
    assert "odemath.h:42]" in err  # the engine's own words, printed as text
    partial = tmp_path / "tiny__base__ode.mcap.partial"
    assert partial.exists() and read_trace(partial, recover=True).status == "incomplete"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["foxglove-layout.json", "tiny.foxglove-layout.json",
                                                          "tiny.yaml", "tiny__base__ode.mcap.partial",
                                                          "tiny__base__ode.outcome.json"]  # fmt: skip


def _in_the_long_step(tmp_path: Path, *extra: str):  # noqa: ANN202 - a Popen
    """PyBullet inside its first step of 300 coincident spheres (the build takes about 0.2 s)."""
    needs("pybullet")
    source = tmp_path / "pile.yaml"
    source.write_text(PILE.format(duration=0.5, budget="", count=300))
    proc = start("run", str(source), "--backend", "pybullet", "--out", str(tmp_path / "out"), *extra)
    worker_of(proc)
    partial = tmp_path / "out" / "pile__base__pybullet.mcap.partial"
    deadline = time.monotonic() + 60
    while not partial.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(1.0)  # the trace is open: the first step has begun
    return proc


@pytest.mark.slow
def test_a_second_signal_ends_a_run_at_once_inside_a_long_engine_call(tmp_path: Path) -> None:
    proc = _in_the_long_step(tmp_path)
    proc.send_signal(signal.SIGTERM)
    time.sleep(0.5)
    assert proc.poll() is None  # the engine has not returned: the first signal waits for it
    sent = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 143 and time.monotonic() - sent < 2.0, err
    trace = tmp_path / "out" / "pile__base__pybullet.mcap"
    wait_released(trace)
    assert read_trace(trace, recover=True).status == "incomplete"  # kept up to its last chunk


@pytest.mark.slow
def test_one_signal_ends_a_run_stuck_in_an_engine_call_after_the_grace_period(tmp_path: Path) -> None:
    """About 11 s: the grace period is 10 s (runner.exec.pool.STOP_GRACE)."""
    from runner.exec.pool import STOP_GRACE

    proc = _in_the_long_step(tmp_path)
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and STOP_GRACE - 1 < time.monotonic() - sent < STOP_GRACE + 5, err
    assert "Traceback" not in err


@pytest.mark.slow
def test_timeout_ends_a_run_stuck_in_an_engine_call(tmp_path: Path) -> None:
    """--timeout 3: SIGTERM at 3 s (the engine does not return), SIGKILL 5 s later; about 9 s."""
    proc = _in_the_long_step(tmp_path, "--timeout", "3")
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 3, out + err
    assert "pile · base · pybullet: timed out: no result after 3 s (world.budget, or --timeout); " \
           "stopped by signal 9" in out  # fmt: skip
    assert read_trace(tmp_path / "out" / "pile__base__pybullet.mcap", recover=True).status == "incomplete"


@pytest.mark.slow
def test_a_run_whose_cost_per_step_explodes_is_stopped_naming_the_cost(tmp_path: Path) -> None:
    """1000 coincident spheres on DART, 50 simulated seconds, a 20 s budget in the scenario. About 6 s."""
    needs("dart")
    source = tmp_path / "pile.yaml"
    source.write_text(PILE.format(duration=50, budget=", budget: 20", count=1000))
    started = time.monotonic()
    proc = start("run", str(source), "--backend", "dart", "--out", str(tmp_path / "out"))
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, out + err
    assert time.monotonic() - started < 20
    text = " ".join(out.split())
    assert "each step costs" in text and "over the wall-clock budget of 20 s" in text, text
    trace = read_trace(tmp_path / "out" / "pile__base__dart.mcap")
    assert trace.status == "engine-failure" and 0 < trace.times[-1] < 50
