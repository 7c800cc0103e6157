"""Engine blow-ups on every real engine: exit 3 naming the body, the time and the last good state; the
trace is complete up to the last good step and marked engine-failure.

The scenario: a 0.1 m sphere (density 1000, m = 4.18879 kg) falls freely from z = 10 m at dt = 0.01 s;
at t = 0.5 s (step 50) a `kick` input applies 1e9 N for one step, so ODE's step gives it
v = 1e9 * 0.01 / 4.18879 - g*dt = 2.387e6 m/s, past the runner's MAX_SPEED (1e4 m/s). The run must
stop at t = 0.51 with the state of t = 0.50 as the last good one: semi-implicit Euler gives
z_50 = 10 - g*dt^2 * 50*51/2 = 8.749225 m and v_50 = -g * 0.5 = -4.905 m/s.

Found on the way: PyBullet clamped a free body's speed to 100 m/s (btMultiBody's default
maxJointVelocity also applies to the base), so the kicked sphere flew on at exactly 100.0 m/s and the
run "passed", and a 12 s free fall ended at -100 m/s instead of ODE's -117.72; lifted in 10beb3d.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from backends.registry import is_installed
from reports.trace_reader import read_trace
from runner.sim.blowup import MAX_SPEED
from tests.engines import ENGINES

G = 9.81
DT = 0.01
KICK_STEP = 50
Z_LAST = 10.0 - G * DT * DT * KICK_STEP * (KICK_STEP + 1) / 2  # 8.749225
V_LAST = -G * DT * KICK_STEP  # -4.905
#: free fall, m and m/s: float64 engines integrate exactly this way (backends/testing/tolerances.py:
#: 1.8e-15 measured on PyBullet); ODE in single precision rounds z (ulp 9.5e-7 at 10 m) and each of the
#: 50 velocity updates, 2.8e-7/1.4e-6 measured at 2 m over 40 steps there, so 2e-5 here.
TOL = {"default": 1e-6, "ode": 2e-5}

SCENARIO = f"""\
schema_version: 1
scenario: kick
world: {{gravity: [0, 0, -{G}], dt: {DT}, duration: 2}}
bodies:
  rocket: {{sphere: 0.1, density: 1000, pos: [0, 0, 10]}}
inputs: [{{at: {KICK_STEP * DT}, event: kick}}]
on:
  kick: [{{force: {{body: rocket, value: [0, 0, 1.0e9]}}}}]
assertions:
  - {{name: reaches-the-end, at: end, check: time > 1.9}}
"""
REAL = list(ENGINES)


@pytest.fixture(params=REAL)
def engine(request: pytest.FixtureRequest) -> str:
    if not is_installed(request.param):
        pytest.skip(f"engine not installed: {request.param}")
    return str(request.param)


def test_the_kick_exceeds_the_speed_limit_by_far() -> None:
    mass = 1000 * 4 / 3 * np.pi * 0.1**3
    assert 1.0e9 * DT / mass > 100 * MAX_SPEED


def test_blow_up_exits_3_naming_body_time_and_last_good_state(tmp_path: Path, engine: str) -> None:
    path = tmp_path / "kick.yaml"
    path.write_text(SCENARIO)
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", str(path), "--backend", engine, "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    out = " ".join(done.stdout.split())  # the console may wrap long lines
    assert done.returncode == 3, out + done.stderr
    assert "Traceback" not in done.stderr
    assert "body `rocket`" in out, out
    when = re.search(r"\bt=(\d+\.\d+)", out)
    assert when and float(when.group(1)) == pytest.approx((KICK_STEP + 1) * DT), out
    match = re.search(r"last good state of `rocket`: (\{.*?\})", out)
    assert match, out
    last_good = json.loads(match.group(1))
    assert set(last_good) == {"time", "pos", "vel", "angvel"}  # the same record whichever engine found it
    tol = TOL.get(engine, TOL["default"])
    assert last_good["time"] == pytest.approx(KICK_STEP * DT, abs=1e-12)
    assert last_good["pos"][2] == pytest.approx(Z_LAST, abs=tol)
    assert last_good["vel"][2] == pytest.approx(V_LAST, abs=tol)

    trace = read_trace(tmp_path / f"kick__base__{engine}.mcap")  # finished: no recover needed
    assert trace.complete and trace.status == "engine-failure"
    assert trace.summary["failure_detail"]["body"] == "rocket"
    assert trace.summary["failure_detail"]["time"] == pytest.approx((KICK_STEP + 1) * DT)
    np.testing.assert_array_equal(np.round(trace.times * 1e9), np.round(np.arange(KICK_STEP + 1) * DT * 1e9))
    k = np.arange(KICK_STEP + 1)
    rocket = trace.bodies["rocket"]
    np.testing.assert_allclose(rocket.pos[:, 2], 10.0 - G * DT * DT * k * (k + 1) / 2, rtol=0, atol=tol)
    np.testing.assert_allclose(rocket.vel[:, 2], -G * DT * k, rtol=0, atol=tol)
    assert rocket.pos[-1, 2] == pytest.approx(last_good["pos"][2], abs=1e-6)  # the trace's last = last good
    assert any(log.level == "error" and "rocket" in log.message for log in trace.logs)


TINY = """\
schema_version: 1
scenario: tiny
world: {dt: 0.01, duration: 0.5}
bodies:
  ground: {plane: {}, motion: static}
  grain: {box: [0.003, 0.003, 0.003], mass: 1e-9, pos: [0, 0, 0.1]}
"""


def test_an_engine_that_aborts_the_process_is_exit_3_under_isolate(tmp_path: Path) -> None:
    """ODE in single precision aborts (SIGABRT, an internal assertion in _dNormalize4) on this 1 ug grain
    (principal moments 1.5e-15 kg m^2) landing on the ground; --isolate reports it as exit 3 with the
    signal and keeps the partial trace. Measured before the fix: the abort message holds
    "[/root/.../odemath.h:42]", which Rich read as a closing markup tag: MarkupError, exit 1."""
    if not is_installed("ode"):
        pytest.skip("engine not installed: ode")
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", str(path), "--backend", "ode", "--out", str(tmp_path), "--isolate"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 3, done.stdout + done.stderr
    assert "Traceback" not in done.stderr
    text = " ".join((done.stdout + done.stderr).split())
    assert "crashed (signal 6)" in text and "odemath.h:42]" in text
    partial = tmp_path / "tiny__base__ode.mcap.partial"
    assert partial.exists() and read_trace(partial, recover=True).status == "incomplete"
