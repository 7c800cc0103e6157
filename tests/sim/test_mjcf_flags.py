"""An MJCF file's `<option><flag .../>` settings (docs/robots.md, "MJCF as MuJoCo reads it"): contacts off is
part of the model on every engine; the others are simulation options, MuJoCo's own with `world: {options:
model}` and not applied with the scenario's options, on MuJoCo as on every other engine.

dm_control's finger disables gravity: before, MuJoCo kept the file's flag for the whole world under the
scenario's options (the finger floated) while the other engines, which read no flags, let it fall.

The check: a free ball released at rest at z0 = 1 m, dt = h = 2 ms, n = 50 steps. Semi-implicit Euler, which
every engine here integrates a free body with, gives z_n = z0 - g h^2 n (n + 1) / 2 exactly (the velocity is
updated first: v_k = -g h k, z_n = z0 + h sum v_k); the tolerance is the rounding of n additions at the
engine's precision. With the flag honoured (MuJoCo, `options: model`) the ball stays at z0.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.registry import get_backend
from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from runner.language.mjcf import load_mjcf
from runner.sim.run import run_loaded
from tests.engines import ENGINES

G, H, STEPS, Z0 = 9.81, 0.002, 50, 1.0
BALL = """<mujoco>
  <option timestep="0.002"><flag gravity="disable"/></option>
  <worldbody>
    <body name="ball" pos="0 0 1">
      <freejoint/>
      <geom type="sphere" size="0.05" mass="1"/>
    </body>
  </worldbody>
</mujoco>
"""
SCENARIO = """schema_version: 1
scenario: flags
world: {{gravity: [0, 0, -9.81], dt: 0.002, duration: 0.1{options}}}
robots:
  m: {{mjcf: ball.xml}}
"""


def _final_z(tmp_path: Path, engine: str, options: str = "") -> float:
    (tmp_path / "ball.xml").write_text(BALL)
    (tmp_path / "flags.yaml").write_text(SCENARIO.format(options=options))
    result = run_loaded(load_scenario(tmp_path / "flags.yaml"), engine, tmp_path / engine)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    return float(read_trace(result.trace).bodies["m.ball"].pos[-1][2])


@pytest.mark.parametrize("engine", ENGINES)
def test_a_files_gravity_flag_is_not_the_worlds_with_the_scenarios_options(tmp_path: Path, engine: str) -> None:
    z = _final_z(tmp_path, engine)
    expected = Z0 - G * H * H * STEPS * (STEPS + 1) / 2
    tol = STEPS * 4 * get_backend(engine).precision.eps * Z0
    assert z == pytest.approx(expected, abs=tol), (engine, z, expected)


def test_mujoco_honours_the_files_gravity_flag_with_the_models_options(tmp_path: Path) -> None:
    if "mujoco" not in ENGINES:
        pytest.skip("MuJoCo is not installed")
    assert _final_z(tmp_path, "mujoco", ", options: model") == pytest.approx(Z0, abs=1e-12)


def test_the_flags_are_named_in_the_models_notes(tmp_path: Path) -> None:
    (tmp_path / "ball.xml").write_text(BALL.replace('gravity="disable"', 'gravity="disable" contact="disable"'))
    notes = load_mjcf(tmp_path / "ball.xml").notes
    assert any('`<flag contact="disable"/>` (line 2)' in n and "touch nothing" in n for n in notes), notes
    assert any('`<flag gravity="disable"/>`' in n and "not applied" in n for n in notes), notes
