"""The expressions' ``eps``: the running engine's machine epsilon (backends.types.Precision), with which a
tolerance adds the rounding bound of docs/semantics.md ("Rounding"): (n + 1) eps (X + V t) on a position
after n steps. ODE (panda3d, float32) misses the free-fall formula by a few 1e-6 m after 100 steps, far
above 1e-9 and far below its bound (2.4e-4 m); a float64 engine is held to 1e-9 + 4e-13."""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.registry import is_installed
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

FALL = """\
schema_version: 1
scenario: fall
params: {z0: 10.0}
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 1.0}
bodies:
  ball: {sphere: 0.1, density: 1000, pos: [0, 0, "${z0}"]}
assertions:
  - {name: epsilon, at: end, value: eps, near: EPS, tol: 0}
  - name: height-with-rounding
    at: end
    value: ball.pos.z
    near: param.z0 - g*dt*dt*round(time/dt)*(round(time/dt) + 1)/2
    tol: 1e-9 + (round(time/dt) + 1)*eps*(param.z0 + g*time*time)
  - name: height-without-rounding
    at: end
    value: ball.pos.z
    near: param.z0 - g*dt*dt*round(time/dt)*(round(time/dt) + 1)/2
    tol: 1e-9
"""


@pytest.mark.parametrize(("backend", "eps", "exact"), [("fake", 2.0**-52, True), ("ode", 2.0**-23, False)])
def test_eps_is_the_engine_precision_and_bounds_its_rounding(
    tmp_path: Path, backend: str, eps: float, exact: bool
) -> None:
    if not is_installed(backend):
        pytest.skip(f"{backend} is not installed")
    path = tmp_path / "fall.yaml"
    path.write_text(FALL.replace("EPS", repr(eps)))
    result = run_loaded(load_scenario(path, None), backend, tmp_path / backend)
    verdicts = {v.name: v for v in result.verdicts}
    assert verdicts["epsilon"].passed
    with_rounding = verdicts["height-with-rounding"]
    assert with_rounding.passed
    n, z0, g, t = 100, 10.0, 9.81, 1.0
    assert with_rounding.tolerance == pytest.approx(1e-9 + (n + 1) * eps * (z0 + g * t * t), rel=1e-12)
    # float64 (the fake backend's exact Euler) meets 1e-9 alone; ODE's float32 does not, by far
    assert verdicts["height-without-rounding"].passed is exact
    if not exact:
        assert 1e-7 < (with_rounding.deviation or 0.0) < with_rounding.tolerance / 10
