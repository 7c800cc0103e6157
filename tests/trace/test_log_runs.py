"""The Log does not list an event delivered on every step one line at a time (runner/trace/repeats.py):
it shows the first delivery of a run and, when the run ends, one line that counts it; /events keeps every
delivery. Read back with our reader; the conformance pendulum (a `tick` input every step) on a real engine."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from backends.registry import is_installed
from reports import trace_format as tf
from reports.trace_reader import read_trace
from runner.trace.process import BackgroundTraceWriter
from runner.trace.writer import TraceWriter
from tests.paths import ROOT

from .test_trace import DT, joints_at, make_meta, states_at


def _write(path: Path, writer: type = TraceWriter) -> Path:
    """Steps 0-49 (dt 0.04). ``tick`` on every step 0-19, not on 20, again on 21-23, and on 30 alone;
    ``hit`` twice on step 5 (two deliveries on one step are a run); ``door`` on steps 40 and 42 (not
    consecutive: two lines); ``spin`` on every step from 45 to the end."""
    w = writer(path, make_meta())
    for k in range(50):
        t = k * DT
        for name, steps in (("tick", [*range(20), 21, 22, 23, 30]), ("hit", [5, 5]), ("door", [40, 42]),
                            ("spin", range(45, 50))):  # fmt: skip
            for _ in range(list(steps).count(k)):
                w.event(t, name, "input" if name != "hit" else "collision", {"n": k} if name == "hit" else None)
        w.step(t, states_at(t), joints_at(t), [], {"door_open": False, "count": float(k)})
    w.verdicts(49 * DT, [{"name": "ok", "passed": True, "measured": 1, "expected": 1}])
    return w.finish("passed", {})


@pytest.mark.parametrize("writer", [TraceWriter, BackgroundTraceWriter])
def test_a_run_of_deliveries_is_one_line_and_its_count(tmp_path: Path, writer: type) -> None:
    trace = read_trace(_write(tmp_path / "runs.mcap", writer))
    logs = [(round(lg.t / DT, 6), lg.message) for lg in trace.logs if lg.name == tf.LOGGER_EVENT]
    assert logs == [
        (0, "tick (input)"),
        (5, 'hit (collision) {"n":5}'),
        (6, "hit (collision) fired 2 times, on every step from 0.2 s to 0.2 s"),
        (20, "tick (input) fired 20 times, on every step from 0 s to 0.76 s"),  # stamped: the step it missed
        (21, "tick (input)"),
        (24, "tick (input) fired 3 times, on every step from 0.84 s to 0.92 s"),
        (30, "tick (input)"),  # alone: no count
        (40, "door (input)"),
        (42, "door (input)"),
        (45, "spin (input)"),
        (49, "spin (input) fired 5 times, on every step from 1.8 s to 1.96 s"),  # lasted to the end
    ]
    assert [lg.name for lg in trace.logs][-1] == tf.LOGGER_VERDICT  # the runs come before the verdicts' line
    times = [lg.t for lg in trace.logs]
    assert times == sorted(times), "the Log is in time order"
    # /events has every delivery, with its detail
    assert len(trace.events) == 24 + 2 + 2 + 5
    assert [e.detail for e in trace.events if e.name == "hit"] == [{"n": 5}, {"n": 5}]


def test_the_same_calls_write_the_same_bytes(tmp_path: Path) -> None:
    a = _write(tmp_path / "a.mcap").read_bytes()
    assert a == _write(tmp_path / "b.mcap", BackgroundTraceWriter).read_bytes()


@pytest.mark.skipif(not is_installed("mujoco"), reason="MuJoCo not installed")
def test_the_conformance_pendulum_logs_its_tick_once(tmp_path: Path) -> None:
    """06_pendulum delivers `tick` on every step (dt 0.002): 1 s is 500 deliveries, two Log lines."""
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", "scenarios/conformance/06_pendulum.yaml", "--backend", "mujoco",
         "--set", "world.duration=1", "--out", str(tmp_path), "--quiet"],
        cwd=ROOT, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode in (0, 1), done.stderr[-2000:]
    (path,) = tmp_path.glob("*.mcap")
    trace = read_trace(path)
    assert sum(e.name == "tick" for e in trace.events) == 500
    ticks = [(lg.t, lg.message) for lg in trace.logs if lg.message.startswith("tick")]
    assert ticks == [(0.0, "tick (input)"), (1.0, "tick (input) fired 500 times, on every step from 0 s to 0.998 s")]
