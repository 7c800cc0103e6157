"""An MJCF joint's `ref` (its qpos0: the file's zero configuration) on every engine: a joint reads its
position from the file's zero, so a start of 0.5 reads 0.5 at t = 0 whatever `ref` is, and a range counts
from the same zero (MuJoCo's range is on qpos, ref included). MuJoCo read qpos itself (0.6 for ref 0.1),
the other engines 0.5.

The model: a hinge (ref 0.1 rad, given in radians) and a hinge whose ref is given in degrees (MJCF's
default angle unit: 5.729578 deg = 0.1 rad), each with a 1 kg rod, and a slide (ref 0.2 m) carrying a
0.5 kg box, no gravity, fixed base, nothing touching. Started at 0.5 with rate 2 (rad/s, m/s): with no
force on any coordinate each moves at its rate, q(t) = 0.5 + 2 t exactly in a semi-implicit Euler step.
Tolerance: ODE's first-order rotation update turns a hinge by 2 atan(w h / 2) per step, (w h)^3 / 12
short (docs/backends/ode.md), over n steps, plus the rounding of each step's sum in the engine's precision
(float32 on ODE: the angle is read from its bodies' single-precision orientations), a few eps (|q| + 1) per
step.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backends.registry import KNOWN_BACKENDS, get_backend, is_installed
from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

pytestmark = pytest.mark.slow
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in) and is_installed(n)]
H, T, W, Q0 = 0.002, 0.1, 2.0, 0.5
MODEL = """<mujoco>
  {compiler}
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="j" type="hinge" axis="0 1 0" ref="{ref}"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" mass="1" contype="0" conaffinity="0"/>
    </body>
    <body name="cart" pos="0 2 1">
      <joint name="s" type="slide" axis="1 0 0" ref="0.2" range="-1 1" limited="true"/>
      <geom type="box" size="0.05 0.05 0.05" mass="0.5" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""
UNITS = {"radian": ('<compiler angle="radian"/>', "0.1"), "degree": ("", "5.729578")}


@pytest.mark.parametrize("unit", sorted(UNITS))
@pytest.mark.parametrize("engine", ENGINES)
def test_a_joint_reads_from_the_files_zero_whatever_its_ref(tmp_path: Path, engine: str, unit: str) -> None:
    compiler, ref = UNITS[unit]
    (tmp_path / "ref.xml").write_text(MODEL.format(compiler=compiler, ref=ref))
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"schema_version: 1\nscenario: ref\nworld: {{dt: {H}, duration: {T}, gravity: [0, 0, 0]}}\n"
                        "bodies: {ground: {plane: {}, motion: static}}\n"
                        "robots:\n  r: {mjcf: ref.xml, fixed: true,\n"
                        f"      initial: {{joints: {{j: {{pos: {Q0}, vel: {W}}},\n"
                        f"                          s: {{pos: {Q0}, vel: {W}}}}}}}}}\n")  # fmt: skip
    loaded = load_scenario(scenario, None)
    result = run_loaded(loaded, engine, tmp_path / "out")
    trace = read_trace(result.trace)
    times = trace.times
    n = np.round(times / H)
    expected = Q0 + W * times
    for joint, turns in (("r.j", True), ("r.s", False)):
        q = trace.joints[joint].position
        assert q[0] == pytest.approx(Q0, abs=1e-12), (joint, q[0])  # the start, as given, at t = 0
        eps = get_backend(engine).precision.eps
        tol = n * ((W * H) ** 3 / 12 if turns else 0.0) + 4 * (n + 1) * eps * (np.abs(expected) + 1)
        assert np.all(np.abs(q - expected) <= tol), (joint, float(np.max(np.abs(q - expected) - tol)))
