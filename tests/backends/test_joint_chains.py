"""Several joints in one MJCF body on every engine (backends/_kit/chains.py), against MuJoCo on the same file.

The body: a 1 kg ball 0.5 m below a pivot, on a hinge about x then a hinge about y through the pivot (a
spherical pendulum in two angles), released at rest at (0.3, 0.2) rad, dt = h = 1 ms, T = 0.5 s. MuJoCo
runs the two joints natively; PyBullet, DART and ODE run a chain world - hx - D1 - hy - ball through one
light body D1 (mass and inertia ``chain_light`` of the ball's: the kit's ``LIGHT``, 1e-4, or the
engine's own, ODE's 1e-3).

Tolerances (A = |(0.3, 0.2)| = 0.36 rad the swing's size, w = sqrt(g / L) its rate):

* the light body changes the accelerations by a relative ``chain_light`` at most (the module's bound, one light
  body), so the angles by at most ``chain_light A (w T)^2`` over T (a relative change d of q'' moves q by
  d A (w t)^2 / 2 for w t ~ 1; doubled);
* PyBullet, DART and MuJoCo (its Euler integrator, no damping) all step the joint coordinates by
  semi-implicit Euler on the same equations, so beyond that only rounding separates them (n eps A);
* ODE steps bodies in maximal coordinates (constraint rows, not joint coordinates), a different first-order
  method: each is within A w h / 2 of the truth (semi-implicit Euler's amplitude error), so they differ by
  up to A w h, plus its float32 rounding n eps A.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from backends.registry import KNOWN_BACKENDS, get_backend, is_installed
from reports.trace_reader import Trace, read_trace
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

pytestmark = pytest.mark.slow
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in) and is_installed(n) and n != "mujoco"]
G, L, H, T = 9.81, 0.5, 0.001, 0.5
START = (0.3, 0.2)
TWO_HINGES = """<mujoco model="two">
  <worldbody>
    <body name="bob" pos="0 0 1">
      <joint name="hx" type="hinge" axis="1 0 0"/>
      <joint name="hy" type="hinge" axis="0 1 0"/>
      <geom type="sphere" size="0.05" pos="0 0 -0.5" mass="1" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""
SCENARIO = f"""schema_version: 1
scenario: two-hinges
world: {{gravity: [0, 0, {-G}], dt: {H}, duration: {T}}}
bodies:
  ground: {{plane: {{}}, motion: static, pos: [0, 0, -1]}}
robots:
  p:
    mjcf: two.xml
    initial: {{joints: {{hx: {START[0]}, hy: {START[1]}}}}}
"""


def _run(tmp_path: Path, engine: str) -> Trace:
    (tmp_path / "two.xml").write_text(TWO_HINGES)
    (tmp_path / "two.yaml").write_text(SCENARIO)
    result = run_loaded(load_scenario(tmp_path / "two.yaml"), engine, tmp_path / engine)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    return read_trace(result.trace)


@pytest.fixture(scope="module")
def mujoco(tmp_path_factory: pytest.TempPathFactory) -> Trace:
    if not is_installed("mujoco"):
        pytest.skip("MuJoCo (the `mujoco` extra) runs the file's joints natively: the reference")
    return _run(tmp_path_factory.mktemp("mujoco"), "mujoco")


@pytest.mark.parametrize("engine", ENGINES)
def test_two_hinges_in_one_body_swing_as_on_mujoco(tmp_path: Path, engine: str, mujoco: Trace) -> None:
    trace = _run(tmp_path, engine)
    amplitude, rate = math.hypot(*START), math.sqrt(G / L)
    steps = T / H
    backend = get_backend(engine)
    bound = backend.chain_light * amplitude * (rate * T) ** 2 + steps * backend.precision.eps * amplitude
    if engine == "ode":
        bound += amplitude * rate * H
    swing = 0.0
    for joint in ("p.hx", "p.hy"):
        q, ref = trace.joints[joint].position, mujoco.joints[joint].position
        assert q[0] == pytest.approx(ref[0], abs=1e-12)  # both start at the file's start
        swing = max(swing, float(np.ptp(ref)))
        gap = float(np.max(np.abs(q - ref)))
        assert gap <= bound, (engine, joint, gap, bound)
    assert swing > 0.3  # the pendulum swung (both angles through about their zero), not a still comparison
