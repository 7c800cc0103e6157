"""/sensors (docs/trace-format.md): the sensor quantities a scenario reads, written per recorded step, read back
by name; the same bytes from the run's own writer and from --trace-process."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from reports import trace_format as tf
from reports.trace_reader import read_trace

CASE = Path(__file__).resolve().parents[2] / "scenarios" / "conformance" / "19_joint_reaction.yaml"


def _run(out: Path, *extra: str) -> Path:
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", str(CASE), "-b", "pybullet", "--variant", "turned", "--out", str(out),
         *extra],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    return out / "conformance-joint-reaction__turned__pybullet.mcap"


def test_sensor_quantities_are_a_channel_read_back_by_name(tmp_path: Path) -> None:
    path = _run(tmp_path / "a")
    trace = read_trace(path)
    names = json.loads(trace.scenario[tf.KEY_SENSORS])
    assert names == sorted({"shoulder.reaction.force.x", "shoulder.reaction.force.y", "shoulder.reaction.force.z",
                            "shoulder.reaction.torque.x", "shoulder.reaction.torque_body.y"})  # fmt: skip
    assert tf.TOPIC_SENSORS in trace.channels
    times, torque = trace.series("shoulder.reaction.torque.x")
    assert list(times) == list(trace.times)  # every recorded step, the initial state included
    # the arm's static torque m g l = 2 x 9.81 x 0.5 about world x (conformance 19, turned), to the trace's 1e-9
    assert torque[-1] == pytest.approx(9.81, abs=1e-9)
    assert trace.sensors["shoulder.reaction.torque_body.y"][-1] == pytest.approx(-9.81, abs=1e-9)
    assert trace.sensors["shoulder.reaction.force.z"][0] == 0.0  # nothing before the first step


def test_the_trace_process_writes_the_same_bytes(tmp_path: Path) -> None:
    assert _run(tmp_path / "a").read_bytes() == _run(tmp_path / "b", "--trace-process").read_bytes()
