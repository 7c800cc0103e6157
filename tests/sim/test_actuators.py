"""MJCF actuators driven by name (`actuators:`, the `control` action; runner/sim/actuators.py, docs/robots.md
"MJCF actuators") on the four engines: MuJoCo runs the file's actuator (its ctrl set each step), the others
MuJoCo's force law by the runner. A 1 x 0.1 x 0.1 m rod of 1 kg on a hinge about z, no gravity:
I = (1 + 0.01)/12 = 0.0841667 kg m^2.

Numbers: a constant torque integrates exactly under semi-implicit Euler (omega = tau t/I); a position
actuator is the recurrence v+ = v + h (kp e - kv v)/I on the runner's side (explicit, the state at the step's
start) and v+ = (v + h kp e/I)/(1 + h kv/I) on MuJoCo (its implicitfast integrator takes the actuator's
velocity term implicitly), q+ = q + h v+, both computed here step by step. Tolerances: the rounding of n
float32 steps ((n + 1) 2^-23 |x| + 1e-12, ODE's states being float32); ODE's first-order rotation update
turns by 2 atan(w h/2) instead of w h (docs/backends/ode.md), (w h)^3/12 short per step, w <= 3.5 rad/s here:
at most 100 x (0.035)^3/12 = 3.6e-4 rad over 100 steps.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from backends.errors import UnsupportedFeature
from backends.registry import check_capabilities, get_backend
from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

pytest.importorskip("mujoco", reason="MJCF is read by MuJoCo's compiler")

ENGINES = ["pybullet", "mujoco", "dart", "ode"]
INERTIA = (1.0 + 0.01) / 12.0
EPS32 = 2.0**-23

MJCF = """\
<mujoco>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 0 1"/>
      <geom type="box" size="0.5 0.05 0.05" mass="1"/>
      <site name="tip" pos="0.5 0 0"/>
    </body>
  </worldbody>
  <actuator>ACTUATOR</actuator>
</mujoco>
"""
SCENARIO = """\
schema_version: 1
scenario: t
world: {gravity: [0, 0, 0], dt: 0.01, duration: DURATION}
bodies:
  ground: {plane: {}, motion: static}
robots:
  r: {mjcf: rod.xml, actuators: {NAME: {ctrl: CTRL}}}
"""


def _write(tmp_path: Path, actuator: str, name: str, ctrl: str, duration: float, extra: str = "") -> Path:
    (tmp_path / "rod.xml").write_text(MJCF.replace("ACTUATOR", actuator))
    path = tmp_path / "t.yaml"
    text = SCENARIO.replace("NAME", name).replace("CTRL", ctrl).replace("DURATION", str(duration))
    path.write_text(text + textwrap.dedent(extra))
    return path


def _run(path: Path, engine: str) -> dict[str, float]:
    pytest.importorskip({"pybullet": "pybullet", "mujoco": "mujoco", "dart": "dartpy", "ode": "panda3d"}[engine])
    result = run_loaded(load_scenario(path, None), engine, None)
    assert result.status == "passed", [(v.name, v.measured) for v in result.verdicts if not v.passed]
    return {v.name: float(v.value) for v in result.verdicts if v.value is not None}


def _bound(x: float, steps: int) -> float:
    return (steps + 1) * EPS32 * abs(x) + 1e-12


@pytest.mark.parametrize("engine", ENGINES)
def test_a_motor_gives_gear_times_ctrl_within_its_ranges(tmp_path: Path, engine: str) -> None:
    """gear 2, ctrlrange [-2, 2], forcerange [-1, 1]: ctrl 0.4 gives 0.8 N m for 0.2 s; `control` then sets
    ctrl 3, clamped to 2, whose force 2 is clamped to 1: 2 N m for 0.3 s."""
    path = _write(tmp_path, '<motor name="spin" joint="hinge" gear="2" ctrlrange="-2 2" forcerange="-1 1"/>',
                  "spin", "0.4", 0.5, """\
        inputs: [{at: 0.2, event: more}]
        on: {more: [{control: {actuator: r.spin, ctrl: 3}}]}
        assertions:
          - {name: w1, at: 0.2, value: r.hinge.velocity, near: 0, tol: 100}
          - {name: w2, at: end, value: r.hinge.velocity, near: 0, tol: 100}
        """)  # fmt: skip
    m = _run(path, engine)
    first = 0.8 * 0.2 / INERTIA
    assert m["w1"] == pytest.approx(first, abs=_bound(first, 20))
    assert m["w2"] == pytest.approx(first + 2.0 * 0.3 / INERTIA, abs=_bound(first + 2.0 * 0.3 / INERTIA, 50))


def _position_response(kp: float, kv: float, target: float, steps: int, implicit: bool) -> list[float]:
    h, q, v, out = 0.01, 0.0, 0.0, [0.0]
    for _ in range(steps):
        e = target - q
        v = (v + h * kp * e / INERTIA) / (1 + h * kv / INERTIA) if implicit else v + h * (kp * e - kv * v) / INERTIA
        q += h * v
        out.append(q)
    return out


@pytest.mark.parametrize("engine", ENGINES)
def test_a_position_actuator_follows_mujocos_law(tmp_path: Path, engine: str) -> None:
    """`<position kp=20 kv=2>` at ctrl 0.5: the step response at 0.2 s and 1 s, explicit on the runner's side,
    kv implicit on MuJoCo (module docstring; the two differ by 4e-3 rad at 0.2 s)."""
    path = _write(tmp_path, '<position name="servo" joint="hinge" kp="20" kv="2"/>', "servo", "0.5", 1.0, """\
        assertions:
          - {name: q1, at: 0.2, value: r.hinge.position, near: 0, tol: 100}
          - {name: q2, at: end, value: r.hinge.position, near: 0, tol: 100}
        """)  # fmt: skip
    m = _run(path, engine)
    expected = _position_response(20.0, 2.0, 0.5, 100, implicit=engine == "mujoco")
    rotation = 100 * 0.035**3 / 12 if engine == "ode" else 0.0
    assert m["q1"] == pytest.approx(expected[20], abs=_bound(0.5, 20) + rotation)
    assert m["q2"] == pytest.approx(expected[100], abs=_bound(0.5, 100) + rotation)


def test_forcerange_is_the_joints_effort_limit_on_every_engine(tmp_path: Path) -> None:
    path = _write(tmp_path, '<motor name="spin" joint="hinge" gear="2" forcerange="-1 1.5"/>', "spin", "0", 0.1)
    world = build_program(load_scenario(path, None)).world
    assert next(j for j in world.joints if j.name == "r.hinge").dynamics.effort == 3.0  # gear x max |force|


def test_a_site_transmission_is_refused_off_mujoco_before_the_run(tmp_path: Path) -> None:
    path = _write(tmp_path, '<general name="push" site="tip" gear="0 1 0 0 0 0"/>', "push", "1", 0.1)
    world = build_program(load_scenario(path, None)).world
    for engine in ("pybullet", "dart", "ode"):
        with pytest.raises(UnsupportedFeature, match="actuator:native"):
            check_capabilities(get_backend(engine), world)
    check_capabilities(get_backend("mujoco"), world)  # MuJoCo runs the file's actuator itself


def test_an_unknown_actuator_is_located(tmp_path: Path) -> None:
    path = _write(tmp_path, '<motor name="spin" joint="hinge"/>', "spn", "1", 0.1)
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    assert "t.yaml:7:" in str(info.value) and "did you mean `spin`" in str(info.value), str(info.value)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_drive_on_an_mjcf_joint_is_capped_by_its_actuators_forcerange(tmp_path: Path, engine: str) -> None:
    """`drive: {torque: 5}` on the hinge of a file whose motor has gear 2, forcerange [-1, 1]: the joint's
    effort limit is 2 N m on every engine, so omega = 2 t/I (the file's motor, at ctrl 0, adds nothing)."""
    (tmp_path / "rod.xml").write_text(
        MJCF.replace("ACTUATOR", '<motor name="spin" joint="hinge" gear="2" forcerange="-1 1"/>')
    )
    path = tmp_path / "t.yaml"
    path.write_text(
        SCENARIO.replace("actuators: {NAME: {ctrl: CTRL}}", "joints: {hinge: {drive: {torque: 5}}}").replace(
            "DURATION", "0.3"
        )
        + "assertions:\n  - {name: w, at: end, value: r.hinge.velocity, near: 0, tol: 100}\n"
    )
    omega = 2.0 * 0.3 / INERTIA
    assert _run(path, engine)["w"] == pytest.approx(omega, abs=_bound(omega, 30))
