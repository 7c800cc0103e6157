"""Blow-ups are found once, by the runner, with one limit for every engine (runner.sim.blowup.MAX_SPEED).

The adapters check nothing themselves (backends/base.py); a body that leaves the limit on any engine ends
the run as an engine failure that names the body, the time and its last good state.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from runner.language.load import load_scenario
from runner.sim.blowup import MAX_SPEED
from runner.sim.run import run_loaded

# 1e8 N for one step of 0.01 s on the 4 kg box: dv = 2.5e5 m/s, far beyond MAX_SPEED (1e4 m/s) and below
# PyBullet's raised speed cap (1e6 m/s); nothing touches it, so every engine integrates exactly F*dt/m.
_KICK = """schema_version: 1
scenario: blow-up
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
bodies:
  box: {box: [0.2, 0.2, 0.2], density: 500, pos: [0, 0, 1]}
on:
  start: [{force: {body: box, value: [1.0e8, 0, 0]}}]
"""


def test_a_blow_up_is_found_by_the_runner_on_every_engine(backend_name: str, tmp_path: Path) -> None:
    path = tmp_path / "blow_up.yaml"
    path.write_text(_KICK)
    result = run_loaded(load_scenario(path, None, ()), backend_name, None)
    assert result.status == "engine-failure"
    assert result.failure == f"body `box` reached a speed above {MAX_SPEED:g} at t=0.0100 s on {backend_name}"
    assert result.extra["body"] == "box" and result.extra["time"] == pytest.approx(0.01)
    assert result.extra["last_good"]["pos"] == pytest.approx([0.0, 0.0, 1.0], abs=1e-6)  # the state at t = 0
