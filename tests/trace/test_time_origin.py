"""A trace starts at simulated time 0, so that Foxglove's clock with the "Seconds" time format, its Log and its
seek field read simulated seconds (docs/trace-format.md, "Simulated seconds on Foxglove's clock"): the MCAP
summary's first message time is 0 and its last is the scenario's duration, read with `mcap` itself."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from mcap.reader import make_reader

from backends.registry import is_installed
from tests.paths import ROOT


@pytest.mark.skipif(not is_installed("mujoco"), reason="MuJoCo not installed")
def test_a_trace_starts_at_zero_and_ends_at_its_duration(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", "scenarios/factory_physics.yaml", "--backend", "mujoco",
         "--set", "world.duration=4", "--record-every", "4", "--out", str(tmp_path), "--quiet"],
        cwd=ROOT, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode in (0, 1), done.stderr[-2000:]
    (path,) = tmp_path.glob("*.mcap")
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics is not None
    # integer nanoseconds: 0 exactly, and 4 s (100 steps of the file's dt 0.04, the last always recorded) exactly
    assert (summary.statistics.message_start_time, summary.statistics.message_end_time) == (0, 4_000_000_000)
