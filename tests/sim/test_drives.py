"""Joint commands (`drive`, runner/sim/drives.py, docs/semantics.md "Joint commands") on the four engines:
torque mode switched at run time, the effort limit, a slider's equal and opposite forces, a servo-held joint
refused, bad input located. Conformance 22 checks the position mode's step response and tau = I alpha.

The rod: a 1 x 0.1 x 0.1 m box of 1 kg on a hinge about z through its centre, no gravity:
I = m (1 + 0.01)/12 = 0.0841667 kg m^2. A constant torque integrates exactly under semi-implicit Euler
(omega = tau t / I); the rate is read from float64 engines to rounding and from ODE (float32) to a few ulps,
so every rate here is checked to (n + 1) eps32 omega + 1e-12, eps32 = 2^-23 (the looser of the two).
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

ENGINES = ["pybullet", "mujoco", "dart", "ode"]
INERTIA = (1.0 + 0.01) / 12.0
EPS32 = 2.0**-23

ROD = """\
schema_version: 1
scenario: t
world: {gravity: [0, 0, 0], dt: 0.01, duration: 0.5}
bodies:
  rod: {box: [1, 0.1, 0.1], mass: 1, pos: [0, 0, 1]}
joints:
  hinge: {type: hinge, bodies: [rod, environment], axis: [0, 0, 1], anchor: [0, 0, 1], DRIVE}
"""


def _run(tmp_path: Path, text: str, engine: str) -> dict[str, float]:
    """Each assertion's measured value by name (every assertion is written to pass)."""
    pytest.importorskip({"pybullet": "pybullet", "mujoco": "mujoco", "dart": "dartpy", "ode": "panda3d"}[engine])
    path = tmp_path / "t.yaml"
    path.write_text(text)
    result = run_loaded(load_scenario(path, None), engine, None)
    assert result.status == "passed", [(v.name, v.measured, v.expected) for v in result.verdicts if not v.passed]
    return {v.name: float(v.value) for v in result.verdicts if v.value is not None}


def _bound(omega: float, steps: int) -> float:
    return (steps + 1) * EPS32 * abs(omega) + 1e-12


@pytest.mark.parametrize("engine", ENGINES)
def test_torque_changed_at_run_time_then_released(tmp_path: Path, engine: str) -> None:
    """0.2 N m for 20 steps (until the timed event at 0.2 s), then `drive: {torque: 0}`: the rod coasts at
    omega = 0.2 x 0.2 / I = 0.4753 rad/s; then 0.1 N m the other way from 0.4 s: omega falls by 0.1 x 0.1 / I."""
    text = ROD.replace("DRIVE", "drive: {torque: 0.2}") + textwrap.dedent("""\
        inputs: [{at: 0.2, event: coast}, {at: 0.4, event: back}]
        on:
          coast: [{drive: {joint: hinge, torque: 0}}]
          back: [{drive: {joint: hinge, torque: -0.1}}]
        assertions:
          - {name: force-while-held, at: 0.1, value: hinge.force, near: 0, tol: 100}
          - {name: force-coasting, at: 0.3, value: hinge.force, near: 0, tol: 100}
          - {name: coasting, at: 0.3, value: hinge.velocity, near: 0, tol: 100}
          - {name: back, at: end, value: hinge.velocity, near: 0, tol: 100}
        """)
    measured = _run(tmp_path, text, engine)
    coast = 0.2 * 0.2 / INERTIA
    assert measured["coasting"] == pytest.approx(coast, abs=_bound(coast, 30))
    assert measured["back"] == pytest.approx(coast - 0.1 * 0.1 / INERTIA, abs=_bound(coast, 50))
    assert measured["force-while-held"] == 0.2  # `<joint>.force` reads the torque handed out for the step
    assert measured["force-coasting"] == 0.0  # (a hinge without a motor: its motor force is 0)


@pytest.mark.parametrize("engine", ENGINES)
def test_the_effort_limit_caps_the_torque(tmp_path: Path, engine: str) -> None:
    """5 N m asked, the joint's effort limit 0.3 N m: omega = 0.3 t / I (the same cap in position mode: an error
    of 1 rad times kp 100 asks 100 N m, and gets 0.3)."""
    for drive in ("{torque: 5}", "{position: 1, kp: 100}"):
        text = ROD.replace("DRIVE", f"drive: {drive}, dynamics: {{effort: 0.3}}") + (
            "assertions:\n  - {name: rate, at: 0.05, value: hinge.velocity, near: 0, tol: 100}\n"
        )
        omega = 0.3 * 0.05 / INERTIA
        assert _run(tmp_path, text, engine)["rate"] == pytest.approx(omega, abs=_bound(omega, 5)), drive


SLIDER = """\
schema_version: 1
scenario: t
world: {gravity: [0, 0, 0], dt: 0.01, duration: 0.3}
bodies:
  a: {box: [0.2, 0.2, 0.2], mass: 1, pos: [0.5, 0, 1]}
  b: {box: [0.2, 0.2, 0.2], mass: 3, pos: [-0.5, 0, ZB]}
joints:
  s: {type: slider, bodies: [a, b], axis: [1, 0, 0], drive: {torque: 2}}
assertions:
  - {name: va, at: end, value: a.vel.x, near: 0, tol: 100}
  - {name: vb, at: end, value: b.vel.x, near: 0, tol: 100}
  - {name: rate, at: end, value: s.velocity, near: 0, tol: 100}
  - {name: momentum, at: end, value: a.vel.x + 3*b.vel.x, near: 0, tol: 100}
  - name: angular-momentum
    at: end
    value: >-
      (a.pos.z*a.vel.x - a.pos.x*a.vel.z) + 3*(b.pos.z*b.vel.x - b.pos.x*b.vel.z)
      + 0.08/12*(a.angvel.y + 3*b.angvel.y)
    near: 0
    tol: 100
"""


@pytest.mark.parametrize("engine", ENGINES)
def test_a_slider_force_is_equal_and_opposite(tmp_path: Path, engine: str) -> None:
    """A 2 N force on a slider between two free boxes (1 kg and 3 kg, no gravity) on one line: the first
    accelerates at +2/1, the second at -2/3, the slider's rate is 2 (1/1 + 1/3) t."""
    m = _run(tmp_path, SLIDER.replace("ZB", "1"), engine)
    t = 0.3
    assert m["va"] == pytest.approx(2.0 * t, abs=_bound(2.0 * t, 30))
    assert m["vb"] == pytest.approx(-2.0 / 3.0 * t, abs=_bound(2.0 * t, 30))
    assert m["rate"] == pytest.approx(2.0 * (1.0 + 1.0 / 3.0) * t, abs=_bound(2.0 * t, 30))


@pytest.mark.parametrize("engine", ENGINES)
def test_a_slider_force_adds_no_momentum_off_its_line(tmp_path: Path, engine: str) -> None:
    """The same with the second box 0.2 m lower: the forces at the two centres of mass would make a couple
    (0.4 N m); the runner shares it out (as ODE's dJointAddSliderForce), so the pair is a true internal force
    and the angular momentum (about the origin: sum m r x v + I w, I = m 0.08/12) stays 0 within one step's
    share of what the couple would add, |dz F| h = 0.004 kg m^2/s (the couple is computed from the centres at
    the step's start); without the sharing it would be |dz F| t = 0.12. The pair turns as it opens (at most
    w = |dz F| t / I_pair = 0.15 rad/s, I_pair >= 0.8 kg m^2), and an engine stepping the slider in reduced
    coordinates moves along the axis of the step's start, so the linear momentum (0 in exact dynamics; ODE
    keeps it to rounding) may turn by w h of |p| = 0.6 kg m/s per step: at most |p| w t = 0.027 kg m/s."""
    m = _run(tmp_path, SLIDER.replace("ZB", "0.8"), engine)
    assert m["momentum"] == pytest.approx(0.0, abs=0.6 * 0.15 * 0.3)
    assert m["angular-momentum"] == pytest.approx(0.0, abs=0.2 * 2.0 * 0.01)


BAD = [
    ("two modes", "drive: {torque: 1, vel: 0, fmax: 1}", "expected exactly one of position, vel, torque"),
    ("position without kp", "drive: {position: 1}", "position mode needs `kp`"),
    ("gains on a torque", "drive: {torque: 1, kd: 2}", "`kp`, `kd` and `rate` belong to position mode"),
    ("motor and drive", "drive: {torque: 1}, motor: {vel: 0, fmax: 1}", "a joint takes a motor or a drive"),
    ("unknown name", "drive: {torque: state.nope}", "unknown"),
]


@pytest.mark.parametrize(("name", "drive", "message"), BAD, ids=[b[0] for b in BAD])
def test_bad_drives_are_located(tmp_path: Path, name: str, drive: str, message: str) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(ROD.replace("DRIVE", drive))
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    text = str(info.value)
    assert "t.yaml:7:" in text and "joints.hinge" in text and message in text, text


def test_a_drive_action_names_a_slider_or_hinge(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(ROD.replace(", DRIVE", "") + "on:\n  start: [{drive: {joint: hing, torque: 1}}]\n")
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    assert "t.yaml:9:" in str(info.value) and "on.start[0].drive.joint" in str(info.value), str(info.value)
