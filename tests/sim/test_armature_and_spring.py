"""Joint armature and joint springs against their analytic periods, on every engine that declares them (the
others refuse them before the run, naming the capability).

* **Armature** (hand-written: a 1 kg ball 0.5 m below a hinge about y, armature a = 0.25 kg m^2, released at
  theta0 = 0.1 rad): MuJoCo adds a to the joint's mass-matrix entry (dof_armature), PyBullet gears a rotor of
  moment a to the joint (backends/pybullet/_rotors.py), DART raises its implicit damping term by a / h and
  cancels that damping's force (backends/dart/_armature.py), Drake gives the joint's actuator a rotor inertia
  a at gear ratio 1 (its reflected inertia, on the mass matrix's diagonal: backends/drake/_joint_dynamics.py),
  ODE one more velocity row on the joint's axis aiming at the step's start rate with CFM h / a, whose force is
  -a (qdot_new - qdot_old) / h (backends/ode/_joint_dynamics.py).
  Period T = 2 pi sqrt((I + a) / (m g L)) (1 + theta0^2 / 16) with I = m (L^2 + 2/5 r^2); without the armature
  it would be 29 % shorter.
* **Spring** (MJCF: a 0.5 m box, 1 kg, on a vertical hinge at its end, so gravity has no torque about it;
  stiffness k = I (2 pi)^2, started at 0.2 rad from its spring's rest): MuJoCo's passive spring, DART's own
  joint spring (setSpringStiffness), PyBullet's joint torque -k (q - ref) from the step's start
  (backends/pybullet/_springs.py), Drake's RevoluteSpring / PrismaticSpring (explicit, from the step's
  start), ODE's dJointAddHingeTorque / dJointAddSliderForce of -k (q - ref) from each step's start
  (backends/ode/_joint_dynamics.py). Period T = 2 pi sqrt(I / k) = 1 s, exact for any amplitude (linear). The
  last test runs armature and spring together over a grid of k, a and h, hinge and slide, against MuJoCo's own mj_step.

Periods are read from the upward zero crossings (linear interpolation between samples), averaged over the
run. Tolerance, relative: the step changes a harmonic oscillator's frequency by (w h)^2 / 24 for
semi-implicit Euler and by at most (w h)^2 / 2 for DART's implicit spring (its update is v (1 + w^2 h^2) =
v - h w^2 q): bound (w h)^2; the pendulum's next series term 11 theta0^4 / 3072 (3.6e-7); the crossings'
interpolation error (w h)^2 / 6 of a step per crossing. PyBullet's gear is one constraint row, which its
solver meets exactly when nothing else touches (no contacts here).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from backends.errors import UnsupportedFeature
from backends.registry import KNOWN_BACKENDS, get_backend, is_installed
from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

pytestmark = pytest.mark.slow
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in) and is_installed(n)]
G, H = 9.81, 0.001


def _declares(engine: str, capability: str) -> bool:
    return capability in {c.value for c in get_backend(engine).capabilities}


def _period(times: np.ndarray, q: np.ndarray) -> float:
    up = [k for k in range(1, len(q)) if q[k - 1] < 0.0 <= q[k]]
    crossings = [float(times[k - 1] + (times[k] - times[k - 1]) * -q[k - 1] / (q[k] - q[k - 1])) for k in up]
    assert len(crossings) >= 3, crossings
    return (crossings[-1] - crossings[0]) / (len(crossings) - 1)


def _run(tmp_path: Path, engine: str, text: str, capability: str) -> tuple[np.ndarray, np.ndarray] | None:
    path = tmp_path / "s.yaml"
    path.write_text("schema_version: 1\nscenario: periods\n" + text)
    if not _declares(engine, capability):
        with pytest.raises(UnsupportedFeature, match=capability):
            run_loaded(load_scenario(path), engine, tmp_path / engine)
        return None
    result = run_loaded(load_scenario(path), engine, tmp_path / engine)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    trace = read_trace(result.trace)
    if "bob" in trace.bodies:  # the pendulum's angle from the vertical (its joint reads from the start)
        pos = trace.bodies["bob"].pos
        return np.asarray(trace.times, float), np.arctan2(pos[:, 0], 2.0 - pos[:, 2])
    joint = next(iter(trace.joints.values()))
    return np.asarray(trace.joint_times, float), np.asarray(joint.position, float)


@pytest.mark.parametrize("engine", ENGINES)
def test_armature_lengthens_a_pendulums_period_to_that_of_i_plus_armature(tmp_path: Path, engine: str) -> None:
    m, length, r, a, theta0 = 1.0, 0.5, 0.05, 0.25, 0.1
    x0, z0 = length * math.sin(theta0), 2.0 - length * math.cos(theta0)
    text = (
        f"world: {{gravity: [0, 0, {-G}], dt: {H}, duration: 8.5}}\n"
        f"bodies:\n  bob: {{sphere: {r}, mass: {m}, pos: [{x0!r}, 0, {z0!r}]}}\n"
        "joints:\n  hinge: {type: hinge, bodies: [bob, environment], axis: [0, 1, 0], anchor: [0, 0, 2], "
        f"dynamics: {{armature: {a}}}}}\n"
    )
    ran = _run(tmp_path, engine, text, "joint:armature")
    if ran is None:
        return
    inertia = m * (length**2 + 0.4 * r**2)
    omega = math.sqrt(m * G * length / (inertia + a))
    truth = 2 * math.pi / omega * (1 + theta0**2 / 16)
    tolerance = (omega * H) ** 2 * (1 + 1 / 6) + 11 * theta0**4 / 3072
    period = _period(*ran)
    assert abs(period - truth) <= tolerance * truth, (engine, period, truth)


SPRING = """<mujoco>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="spin" type="hinge" axis="0 0 1" stiffness="{k!r}"/>
      <geom type="box" size="0.25 0.02 0.02" pos="0.25 0 0" mass="1" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize("engine", ENGINES)
def test_a_joint_spring_oscillates_with_period_2_pi_sqrt_i_over_k(tmp_path: Path, engine: str) -> None:
    inertia = 1.0 / 12 * (0.5**2 + 0.04**2) + 1.0 * 0.25**2  # the box about the hinge at its end
    omega = 2 * math.pi
    (tmp_path / "spring.xml").write_text(SPRING.format(k=inertia * omega**2))
    text = (
        f"world: {{gravity: [0, 0, {-G}], dt: {H}, duration: 3.5}}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [50, 50, 0]}\n"
        "robots:\n  r: {mjcf: spring.xml, initial: {joints: {spin: 0.2}}}\n"
    )
    ran = _run(tmp_path, engine, text, "joint:stiffness")
    if ran is None:
        return
    period = _period(*ran)
    tolerance = (omega * H) ** 2 * (1 + 1 / 6)
    assert abs(period - 1.0) <= tolerance, (engine, period)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("kind", ["hinge", "slider"])
def test_a_torque_on_a_joint_with_armature_accelerates_it_at_tau_over_i_plus_armature(
    tmp_path: Path, engine: str, kind: str
) -> None:
    """The analytic case: a 2 kg cylinder (r 0.2 m: I = m r^2 / 2 = 0.04 kg m^2 about its axis) on a vertical
    hinge through its axis (gravity does no work), or on a horizontal slider (mass 2 kg), with armature a =
    0.06, driven by a constant torque (force) tau = 0.5 from rest: q'' = tau / (I + a) exactly, so the rate
    is tau t / (I + a) at every step of semi-implicit Euler; tolerance: rounding (the trace's 1e-9, n eps per
    step). Without the armature the rate would be 2.5 times (hinge) or 1.03 times (slider) larger."""
    axis, inertia = ("[0, 0, 1]", 0.04) if kind == "hinge" else ("[1, 0, 0]", 2.0)
    ran = _run(
        tmp_path,
        engine,
        f"world: {{gravity: [0, 0, {-G}], dt: {H}, duration: 0.5}}\n"
        "bodies:\n  ground: {plane: {}, motion: static, pos: [0, 0, -1]}\n"
        "  wheel: {cylinder: {radius: 0.2, length: 0.05}, mass: 2.0, pos: [0, 0, 1]}\n"
        f"joints:\n  axle: {{type: {kind}, bodies: [wheel, environment], axis: {axis}, "
        "drive: {torque: 0.5}, dynamics: {armature: 0.06}}\n",
        "joint:armature",
    )
    if ran is None:
        return
    times, q = ran
    truth = 0.5 * times * (times + H) / (2 * (inertia + 0.06))  # semi-implicit Euler: q_n = a h^2 n (n + 1) / 2
    steps = len(times)
    assert np.all(np.abs(q - truth) <= 1e-9 + steps * get_backend(engine).precision.eps * (np.abs(truth) + 1.0))
    assert q[-1] > 0.0


@pytest.mark.parametrize("engine", ENGINES)
def test_a_bounded_motor_on_a_joint_with_armature_accelerates_it_at_fmax_over_i_plus_armature(
    tmp_path: Path, engine: str
) -> None:
    """The same wheel (I = 0.04 kg m^2, a = 0.06) on a velocity motor far from its target (100 rad/s) with
    fmax = 0.5 N m: the motor pushes at its bound all the time, so the rate is fmax t / (I + a), 2.5 rad/s at
    0.5 s (rounding only). DART's servo constraint computes its impulse without the armature (fmax / I: 6.25
    rad/s), so DART refuses a motor on a joint with armature before the run, naming the armature."""
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: motor\n"
        f"world: {{gravity: [0, 0, {-G}], dt: {H}, duration: 0.5}}\n"
        "bodies:\n  ground: {plane: {}, motion: static, pos: [0, 0, -1]}\n"
        "  wheel: {cylinder: {radius: 0.2, length: 0.05}, mass: 2.0, pos: [0, 0, 1]}\n"
        "joints:\n  axle: {type: hinge, bodies: [wheel, environment], axis: [0, 0, 1], "
        "motor: {vel: 100, fmax: 0.5}, dynamics: {armature: 0.06}}\n"
    )
    if engine == "dart":
        with pytest.raises(UnsupportedFeature, match="armature with a motor"):
            run_loaded(load_scenario(path), engine, tmp_path / engine)
        return
    ran = _run(tmp_path, engine, path.read_text().split("\n", 2)[2], "joint:armature")
    if ran is None:
        return
    times, _ = ran
    trace = read_trace(next((tmp_path / engine).glob("*.mcap")))
    rate = np.asarray(trace.joints["axle"].velocity, float)
    steps = len(times)
    assert np.all(np.abs(rate - 0.5 * times / 0.1) <= 1e-9 + steps * get_backend(engine).precision.eps * 10)


#: A rod on a vertical hinge (I about it: ``ROD_INERTIA``) or a 1 kg box on a horizontal slide: gravity does no
#: work, so the joint is a linear oscillator, omega^2 = k / (I + a), about the spring's rest.
#: (kind, stiffness k, armature a, step h, springref, start from the model's zero)
SPRING_GRID = [
    ("hinge", 0.3335 * (2 * math.pi) ** 2, 0.25, 0.001, 0.0, 0.2),
    ("hinge", 40.0, 0.05, 0.002, 0.3, 0.5),
    ("slide", 20.0, 0.5, 0.005, -0.1, 0.1),
    ("slide", 300.0, 2.0, 0.001, 0.0, -0.15),
]
ROD_INERTIA = 1.0 / 12 * (0.5**2 + 0.04**2) + 1.0 * 0.25**2
OSCILLATOR = """<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="q" type="{kind}" axis="{axis}" stiffness="{k!r}" armature="{a!r}"
             springref="{springref!r}"/>
      <geom type="box" size="0.25 0.02 0.02" pos="0.25 0 0" mass="1" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""
#: DART integrates its joint spring implicitly (its own setSpringStiffness; armature as implicit damping:
#: backends/dart/_armature.py); every other engine declaring both applies -k (q - rest) from the step's start
#: on an inertia I + a, which is MuJoCo's Euler step.
IMPLICIT_SPRING = {"dart"}
#: ODE holds a hinge by constraint rows between the bodies' own coordinates (maximal coordinates): each step
#: moves the rod's COM (r = 0.25 m from the axis) along the chord of its arc, (h W)^2 r / 2 outwards of the
#: anchor at the rate W, and ERP takes back the fraction ERP of that error per step, so the rod runs
#: e = (h W)^2 r / (2 ERP) long and its inertia about the axis is 2 m r e larger: the frequency falls by at most
#: m r^2 h^2 W_max^2 / (2 ERP (I + a)) (W_max = A omega; the mean of W^2 is half that), a phase error growing as
#: omega t, A omega t times that in q. MuJoCo's hinge is a coordinate: no drift. ``ODE_ERP``: ODE's default.
MAXIMAL_COORDINATES = {"ode"}
ODE_ERP = 0.2


def _oscillator(q0: float, rest: float, w2: float, h: float, n: int, implicit: bool) -> np.ndarray:
    """q_0..q_n of semi-implicit Euler (v' = v - h w2 (q - rest)) or, ``implicit``, of the step with the spring
    at the step's end (v' (1 + w2 h^2) = v - h w2 (q - rest)); q' = q + h v' in both; from rest at q0."""
    q, v, out = q0, 0.0, [q0]
    for _ in range(n):
        v = (v - h * w2 * (q - rest)) / (1.0 + w2 * h * h if implicit else 1.0)
        q += h * v
        out.append(q)
    return np.asarray(out)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(("kind", "k", "a", "h", "springref", "q0"), SPRING_GRID)
def test_a_spring_on_a_joint_with_armature_runs_as_mujocos_own_mj_step(
    tmp_path: Path, engine: str, kind: str, k: float, a: float, h: float, springref: float, q0: float
) -> None:
    """Armature and spring together, over a range of k, a and h, hinge and slide, started away from MJCF's
    ``springref`` (radians: the compiler's angle): the joint oscillates about it with omega = sqrt(k / (I + a)).

    * against MuJoCo's own ``mj_step`` on the same file (Euler, the same h, qpos = q0): an engine taking
      the spring from the step's start runs the same map, so only rounding separates them (1e-9, the trace's,
      plus 10 n eps A); DART's implicit spring differs by the two maps' difference, computed here exactly
      (``_oscillator``) and allowed on top; ODE's hinge by its drift in maximal coordinates (bounded at
      ``MAXIMAL_COORDINATES``; measured 1.68e-4 rad at k 40, h 2 ms, where rounding alone allows 1.51e-4, and
      0.306 / 0.168 / 0.085 / 0.041 e-3 at ERP 0.1 / 0.2 / 0.4 / 0.8: as 1 / ERP);
    * against the analytic period 2 pi / omega, as the tests above: (omega h)^2 (1 + 1/6) relative.
    """
    axis, inertia = ("0 0 1", ROD_INERTIA) if kind == "hinge" else ("1 0 0", 1.0)
    xml = OSCILLATOR.format(kind=kind, axis=axis, k=k, a=a, springref=springref)
    (tmp_path / "osc.xml").write_text(xml)
    w2 = k / (inertia + a)
    omega, rest, amplitude = math.sqrt(w2), springref, abs(q0 - springref)
    steps = round(3.5 * 2 * math.pi / omega / h)
    text = (
        f"world: {{gravity: [0, 0, {-G}], dt: {h!r}, duration: {steps * h!r}}}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [50, 50, 0]}\n"
        f"robots:\n  r: {{mjcf: osc.xml, initial: {{joints: {{q: {q0!r}}}}}}}\n"
    )
    ran = _run(tmp_path, engine, text, "joint:stiffness")
    if ran is None:
        return
    times, q = ran
    mujoco = pytest.importorskip("mujoco", reason="MuJoCo's own mj_step is the reference")
    model = mujoco.MjModel.from_xml_string(xml)
    model.opt.timestep = h
    data = mujoco.MjData(model)
    data.qpos[0] = q0
    native = [float(data.qpos[0])]
    for _ in range(steps):
        mujoco.mj_step(model, data)
        native.append(float(data.qpos[0]))
    index = np.rint(times / h).astype(int)
    assert np.all(np.abs(times - index * h) <= 1e-9) and index[-1] == steps
    tolerance = 1e-9 + 10 * steps * get_backend(engine).precision.eps * amplitude
    if engine in IMPLICIT_SPRING:
        explicit, implicit = (_oscillator(q0, rest, w2, h, steps, flag) for flag in (False, True))
        tolerance += float(np.max(np.abs(explicit - implicit)))
    if engine in MAXIMAL_COORDINATES and kind == "hinge":
        drift = 1.0 * 0.25**2 * h**2 * (amplitude * omega) ** 2 / (2 * ODE_ERP * (inertia + a))
        tolerance += amplitude * omega * steps * h * drift
    off = np.abs(q - np.asarray(native)[index])
    assert float(np.max(off)) <= tolerance, (engine, float(np.max(off)), tolerance)
    period = _period(times, q - rest)
    truth = 2 * math.pi / omega
    assert abs(period - truth) <= (omega * h) ** 2 * (1 + 1 / 6) * truth, (engine, period, truth)
