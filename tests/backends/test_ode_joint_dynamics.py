"""ODE's joint armature and joint springs (backends/ode/_joint_dynamics.py), beyond the shared tests
(tests/sim/test_armature_and_spring.py and test_joint_dynamics.py run ODE with the other engines).

Armature a is one more velocity row on the joint's axis, solved in ODE's LCP with the contacts, stops and
motors: unbounded, CFM = h / a, aiming at the rate of the step's start, so its force is -a (qdot' - qdot) / h.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("panda3d.ode")

from panda3d.ode import OdeBody, OdeLMotorJoint, OdeMass, OdeWorld  # noqa: E402 - after the skip guard

from backends.errors import UnsupportedFeature  # noqa: E402
from backends.ode import OdeBackend  # noqa: E402
from backends.ode._joint_dynamics import PARAM_CFM, PARAM_FMAX, PARAM_VEL  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.types import JointDynamics, JointKind, Precision  # noqa: E402
from reports.trace_reader import Trace, read_trace  # noqa: E402
from runner.compile.program import build_program  # noqa: E402
from runner.language.load import load_scenario  # noqa: E402
from runner.sim.run import run_loaded  # noqa: E402

EPS = Precision.FLOAT32.eps


def _run(tmp_path: Path, text: str, name: str = "run") -> Trace:
    path = tmp_path / f"{name}.yaml"
    path.write_text("schema_version: 1\nscenario: armature\n" + text)
    result = run_loaded(load_scenario(path), "ode", tmp_path / name)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    return read_trace(result.trace)


def test_the_lmotor_parameter_numbers_are_odes_and_its_row_is_a_rotor_at_the_target_rate() -> None:
    """OdeLMotorJoint has only numbered parameters (ODE 0.13.1's dParamVel 2, dParamFMax 5, dParamCFM 8). A
    free 2 kg body at rest with the row (target 1.5 m/s, CFM h / a, a = 0.5 kg, unbounded) is a body coupled
    to a rotor of mass a moving at 1.5 m/s: one step leaves both at the momentum balance a 1.5 / (m + a) =
    0.3 m/s (float32 rounding). Wrong numbers leave the body at rest (no FMax) or at another rate."""
    m, a, h, target = 2.0, 0.5, 0.01, 1.5
    world = OdeWorld()
    world.setGravity(0, 0, 0)
    body = OdeBody(world)
    mass = OdeMass()
    mass.setParameters(m, 0, 0, 0, 1, 1, 1, 0, 0, 0)
    body.setMass(mass)
    row = OdeLMotorJoint(world)
    row.attach(body, None)
    row.setNumAxes(1)
    row.setAxis(0, 1, 1, 0, 0)
    row.setParam(PARAM_VEL, target)
    row.setParam(PARAM_FMAX, math.inf)
    row.setParam(PARAM_CFM, h / a)
    world.step(h)
    assert abs(body.getLinearVel()[0] - a * target / (m + a)) <= 10 * EPS
    assert (row.getParam(PARAM_VEL), row.getParam(PARAM_FMAX)) == (target, math.inf)
    row.destroy()
    body.destroy()
    world.destroy()


IMPACT = """world: {{gravity: [0, 0, -9.81], dt: 0.001, duration: 0.4}}
bodies:
  arm: {{box: [0.05, 1.0, 0.05], mass: 1.0, pos: [0, 0, 1]}}
  weight: {{box: [0.1, 0.1, 0.1], mass: 0.5, pos: [0, 0.4, 1.3]}}
joints:
  pivot: {{type: hinge, bodies: [arm, environment], axis: [1, 0, 0], anchor: [0, 0, 1]{dynamics}}}
"""


@pytest.mark.parametrize("armature", [0.0, 0.2])
def test_an_impact_on_an_arm_with_armature_keeps_the_angular_momentum_of_arm_rotor_and_box(
    tmp_path: Path, armature: float
) -> None:
    """A box (0.5 kg, 0.1 m) falls 0.225 m onto a 1 m arm (1 kg) on a horizontal hinge through its centre,
    0.4 m from the axis, with armature a. About the hinge axis x through the anchor, nothing but gravity has a
    moment (the contact forces are equal and opposite at one point, the hinge's anchor force acts at the
    anchor, its other rows' torques are across x, and the armature row is the rotor, whose momentum is
    a qdot): L = I_arm w_arm + m_arm (r_arm x v_arm) + a qdot + m_box (r_box x v_box) + I_box w_box changes by
    h m g x r (moment of gravity from each step's start) and nothing else, impact included. The arm's rate
    after the impact is 2.1 times lower with a = 0.2 than without, and the balance without the term a qdot
    misses by 0.43 N m s. Tolerance: float32 rounding, n eps per step of the terms' sizes, and the trace's 1e-9."""
    dynamics = f", dynamics: {{armature: {armature}}}" if armature else ""
    trace = _run(tmp_path, IMPACT.format(dynamics=dynamics))
    arm, box = trace.bodies["arm"], trace.bodies["weight"]
    anchor, g, h = np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -9.81]), 0.001
    i_arm = 1.0 * (1.0**2 + 0.05**2) / 12  # about x, the arm's principal axis along the hinge
    i_box = 0.5 * (0.1**2 + 0.1**2) / 12  # a cube: the same about every axis
    r_arm, r_box = arm.pos - anchor, box.pos - anchor
    rate = np.asarray(trace.joints["pivot"].velocity, float)
    terms = np.stack([
        i_arm * arm.angvel[:, 0],
        1.0 * np.cross(r_arm, arm.vel)[:, 0],
        armature * rate,
        0.5 * np.cross(r_box, box.vel)[:, 0],
        i_box * box.angvel[:, 0],
    ])
    moments = np.cross(r_arm, 1.0 * g)[:, 0] + np.cross(r_box, 0.5 * g)[:, 0]
    gravity = np.concatenate([[0.0], np.cumsum(h * moments[:-1])])
    balance = terms.sum(axis=0) - terms[:, 0].sum() - gravity
    steps = np.arange(len(balance))
    tolerance = steps * EPS * np.max(np.abs(terms).sum(axis=0)) + 1e-9 * (1 + steps * h * 10)
    assert np.all(np.abs(balance) <= tolerance), float(np.max(np.abs(balance)))
    assert rate[-1] < -1.0  # the arm was hit and turns (at -4.58 rad/s without armature, -2.15 with 0.2)


RAIL = """world: {{gravity: [0, 0, 0], dt: {h}, duration: 1.0}}
bodies:
  table: {{cylinder: {{radius: 0.05, length: 0.05}}, mass: 10, angvel: [0, 0, {w}]}}
  carriage: {{sphere: 0.05, mass: {m}, pos: [{r}, {y0}, 0], vel: [{vx}, {vy}, 0], angvel: [0, 0, {w}]}}
joints:
  spin: {{type: hinge, bodies: [table, environment], axis: [0, 0, 1], motor: {{vel: {w}, fmax: 1.0e6}}}}
  rail: {{type: slider, bodies: [carriage, table], axis: [0, 1, 0], dynamics: {{armature: {a}}}}}
"""


def test_armature_on_a_slider_along_a_turning_rail_slows_its_drift_to_m_over_m_plus_a(tmp_path: Path) -> None:
    """Coverage of the slider pair's row, whose rate carries the decoupling term and whose target takes off the
    change the rail's turning makes (backends/ode/_joint_dynamics.py). A 1 kg carriage on a rail across a table
    held at W = 2 rad/s by its motor, 0.5 m from the axis, starting 0.1 m along the rail at rest on it:
    MuJoCo's equation (m + a) yddot = m W^2 y, so y = y0 cosh(w' t), w'^2 = m W^2 / (m + a). With a = 2:
    y(1 s) - y0 = 0.0744 m against 0.2762 m without armature. Tolerance: the global error bound of a
    first-order one-step map, (h M / 2 L)(e^(L t) - 1), L = max(1, w'^2) and M = w'^2 max(|y|, |ydot|) of the
    solution: 2.4e-4 m at h = 1 ms. (Jdot v taken from each step's start instead of the last step's change:
    1.45e-3 m, the rail's ERP corrections missing; without it the armature does nothing: 0.2 m.)"""
    m, a, w, r, y0, h = 1.0, 2.0, 2.0, 0.5, 0.1, 0.001
    trace = _run(tmp_path, RAIL.format(h=h, w=w, m=m, r=r, y0=y0, vx=-w * y0, vy=w * r, a=a))
    t = np.asarray(trace.joint_times, float)
    q = np.asarray(trace.joints["rail"].position, float)
    w2 = m * w * w / (m + a)
    truth = y0 * np.cosh(math.sqrt(w2) * t) - y0
    lipschitz = max(1.0, w2)
    top = w2 * max(y0 * math.cosh(math.sqrt(w2) * t[-1]), y0 * math.sqrt(w2) * math.sinh(math.sqrt(w2) * t[-1]))
    bound = h * top / (2 * lipschitz) * (math.exp(lipschitz * t[-1]) - 1.0)
    assert float(np.max(np.abs(q - truth))) <= bound, (float(np.max(np.abs(q - truth))), bound)


def test_a_run_with_armature_and_springs_is_byte_identical(tmp_path: Path) -> None:
    """Same scenario, same engine: the same trace, byte for byte (the rows' targets and the springs' forces
    are computed from ODE's float32 state in the same order every step)."""
    xml = (
        '<mujoco><worldbody><body name="rod" pos="0 0 1">'
        '<joint name="q" type="hinge" axis="0 1 0" stiffness="3" armature="0.1" damping="0.05"/>'
        '<geom type="box" size="0.25 0.02 0.02" pos="0.25 0 0" mass="1"/>'
        '<body name="tip" pos="0.5 0 0"><joint name="s" type="slide" axis="1 0 0" stiffness="20" armature="0.3"/>'
        '<geom type="sphere" size="0.05" mass="0.5"/></body></body></worldbody></mujoco>'
    )
    (tmp_path / "m.xml").write_text(xml)
    text = (
        "world: {gravity: [0, 0, -9.81], dt: 0.002, duration: 0.5}\n"
        "bodies:\n  ground: {plane: {}, motion: static}\n"
        "robots:\n  r: {mjcf: m.xml, initial: {joints: {q: 0.3, s: 0.05}}}\n"
    )
    path = tmp_path / "twice.yaml"
    path.write_text("schema_version: 1\nscenario: twice\n" + text)
    traces = []
    for name in ("a", "b"):
        result = run_loaded(load_scenario(path), "ode", tmp_path / name)
        assert result.status == "passed", result.failure
        assert result.trace is not None
        traces.append(Path(result.trace).read_bytes())
    assert traces[0] == traces[1]


def test_armature_or_a_spring_on_a_universal_joint_is_refused_before_the_run() -> None:
    """The language gives dynamics to sliders and hinges only; a world built otherwise (an adapter's caller)
    with armature or a spring on a universal joint is refused by ODE's check, naming the joint."""
    world = w.offset_hinge(kind=JointKind.UNIVERSAL)
    for dynamics in (JointDynamics(armature=0.1), JointDynamics(stiffness=2.0)):
        joint = dataclasses.replace(world.joints[0], axis2=(0.0, 0.0, 1.0), dynamics=dynamics)
        with pytest.raises(UnsupportedFeature, match="`hinge` \\(universal\\).*sliders and hinges only"):
            OdeBackend.check_world(dataclasses.replace(world, joints=(joint,)), OdeBackend.Options())


WHEEL = """<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <body name="wheel" pos="0 0 1">
      <joint name="spin" type="hinge" axis="0 0 1" stiffness="{k!r}" springref="3.0"/>
      <geom type="cylinder" size="0.2 0.025" mass="2" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_a_hinge_spring_winds_past_pi_where_odes_angle_wraps(tmp_path: Path) -> None:
    """ODE's hinge angle lives in (-pi, pi]; a spring is not periodic. A wheel (I = m r^2 / 2 = 0.04 kg m^2, its
    centre on the axis: no drift) on a vertical hinge, at rest at 0 with its spring relaxed at 3 rad, swings
    between 0 and 6 rad, through pi and back, with period 1 s. Against semi-implicit Euler's own recurrence
    (v += -h k (q - 3) / I, q += h v), compared modulo 2 pi (ODE reports its wrapped angle): float32 rounding,
    10 n eps A as the grid of test_armature_and_spring. Read without unwrapping, the spring would pull the wrong
    way from pi on. Run on the adapter itself: the runner's energy watchdog reads the spring's energy from the
    reported, wrapped angle, which jumps by 2 pi there (docs/backends/ode.md)."""
    inertia, h = 0.5 * 2.0 * 0.2**2, 0.001
    k = inertia * (2 * math.pi) ** 2
    (tmp_path / "wheel.xml").write_text(WHEEL.format(k=k))
    path = tmp_path / "wheel.yaml"
    path.write_text(
        f"schema_version: 1\nscenario: wheel\nworld: {{gravity: [0, 0, -9.81], dt: {h}, duration: 1.5}}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [50, 50, 0]}\n"
        "robots:\n  r: {mjcf: wheel.xml}\n"
    )
    world = build_program(load_scenario(path)).world
    spin = next(i for i, j in enumerate(world.joints) if j.name == "r.spin")
    backend = w.make_backend("ode", world)
    q, truth, v, x = [0.0], [0.0], 0.0, 0.0
    for _ in range(1500):
        backend.step()
        q.append(float(backend.joint_states().position[spin]))
        v -= h * k * (x - 3.0) / inertia
        x += h * v
        truth.append(x)
    backend.close()
    assert max(truth) > 5.9 and min(q) < -3.0  # it winds past pi, to 6 rad, and ODE's angle wraps
    off = np.angle(np.exp(1j * (np.asarray(q) - np.asarray(truth))))  # the difference modulo 2 pi
    assert float(np.max(np.abs(off))) <= 10 * len(q) * EPS * 3.0, float(np.max(np.abs(off)))
