"""Joint dynamics (docs/semantics.md, "Joint dynamics") against analytic truths, on every installed engine.

Damping and friction loss are the runner's motor towards rest, bounded by ``f + c |qdot|`` (qdot read after
the last step; runner.sim.joint_dynamics), so the truths are those of the continuous system, and the
tolerances are the step's error (dt = h; the engines integrate with semi-implicit Euler, first order):

* **Damped pendulum** (bob: sphere r, mass m, L below a hinge; I = m (L^2 + 2/5 r^2); damping c; released
  at rest at theta0). Linearised, theta = theta0 e^(-gamma t) (cos wd t + gamma/wd sin wd t) with
  gamma = c/(2 I), whose extremes are exactly |theta(t_k)| = theta0 e^(-gamma t_k) at t_k = k pi/wd. The
  extremes read from the trace are compared with theta0 e^(-gamma t) at their own time. Error budget,
  relative: semi-implicit Euler's energy oscillates by about w h / 2 of the swing (its amplitude by w h / 4)
  and the damping force uses the rate at the start of the step, shifting it by half a step (gamma h / 2 per
  unit gamma t, < w h here); sampling an extreme within a step misses it by at most (w h)^2 / 8; the
  nonlinearity of the swing changes the amplitude by theta0^2 / 16 (the series of the elliptic integral);
  the engine's rounding adds eps per step (float32 on ODE: 3.6e-4 over 3000 steps). Bound:
  2 w h + theta0^2 / 8 + n eps. DART and ODE damp with their own implicit joint damping (native_damping):
  rate / (1 + c h / I) per step instead of (1 - c h / I), the same first-order budget.
* **Implicit damping** (ODE and DART, ``Backend.native_damping``: the engine damps the joint itself): a wheel
  on a hinge through its centre (or a body on a slider), no gravity along the joint, spun at v0, damping c,
  armature a: each step solves (I + a) (v' - v) = -c h v', so v_n = v0 / (1 + c h / (I + a))^n exactly; the
  grid spans c h / (I + a) from 5e-5 to 0.8; from 2.5e-3 up, the explicit -c v of the step's start,
  (1 - c h / (I + a))^n, differs by 3e-4 to 160 % of v0 over 50 steps, far above the bound. Bound: the
  engine's rounding, (n + 1) eps v0 (docs/semantics.md, "Rounding"), plus the trace's 1e-9 quantum.
* **Slider with friction loss** (mass m on a horizontal rail, started at v0, dry friction F): decelerates at
  a = F/m and stops after t* = v0 m / F at d* = v0^2 m / (2 F). Discretely each step removes exactly a h of
  speed until the motor can stop it; positions use the new speed (x += h v), so the distance is short of d*
  by at most one step's travel, v0 h, and the stop comes within one step of t*. The engine's rounding of the
  speed (eps v0 per step, n steps: float32 on ODE) moves the stop by n eps v0 / a and the distance by
  n eps v0 t*.
* **Effort limit** (a body hanging on a vertical slider whose motor holds it, vel 0 with fmax far above its
  weight, but the joint's effort is half the weight): the motor pushes with exactly the effort, so the body
  falls at a = g - effort/m: z = z0 - a t^2 / 2; semi-implicit Euler's position error after n steps is
  a h t / 2; the motor's reported force equals the effort to the solver's rounding (relative 1e-5 covers
  float32).
* **Velocity limit** (a wheel on a vertical hinge through its centre, a motor commanding 5 rad/s with ample
  force on a joint limited to 2 rad/s): the commanded rate is clamped, so the wheel turns at 2 rad/s; the
  motor reaches its rate within a step (MuJoCo's motor row leaves 1e-4 of the change per step, gone after a
  few), so after 0.2 s the rate is 2 rad/s to the solver's rounding (relative 1e-5 covers float32).
* **Armature** (MuJoCo's dof_armature, PyBullet's geared rotor: a wheel on a hinge through its centre, damping
  c, spun at w0): w = w0 e^(-c t / (I + armature)) (DART: its implicit joint inertia, backends/dart/_armature.py;
  Drake: its joint actuator's rotor inertia, backends/drake/_joint_dynamics.py; ODE: one more velocity row with
  CFM h / armature, backends/ode/_joint_dynamics.py); an engine without `joint:armature` refuses it before the run.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from backends.errors import UnsupportedFeature
from backends.registry import KNOWN_BACKENDS, get_backend, is_installed
from reports.trace_reader import Trace, read_trace
from runner.compile.program import build_program
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

pytestmark = pytest.mark.slow
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in) and is_installed(n)]
G = 9.81


def _eps(engine: str) -> float:
    return get_backend(engine).precision.eps


def _run(tmp_path: Path, engine: str, text: str) -> Trace:
    path = tmp_path / "s.yaml"
    path.write_text("schema_version: 1\nscenario: dynamics\n" + text)
    result = run_loaded(load_scenario(path), engine, tmp_path / engine)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    return read_trace(result.trace)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(("mass", "damping"), [(0.5, 0.05), (2.0, 0.4), (5.0, 3.0)])
def test_damped_pendulum_decays_as_exp_minus_c_t_over_2i(
    tmp_path: Path, engine: str, mass: float, damping: float
) -> None:
    length, r, theta0, h, duration = 0.5, 0.05, 0.05, 0.001, 3.0
    x0, z0 = length * math.sin(theta0), 2.0 - length * math.cos(theta0)
    trace = _run(
        tmp_path,
        engine,
        f"world: {{gravity: [0, 0, {-G}], dt: {h}, duration: {duration}}}\n"
        f"bodies:\n  bob: {{sphere: {r}, mass: {mass}, pos: [{x0!r}, 0, {z0!r}]}}\n"
        "joints:\n  hinge: {type: hinge, bodies: [bob, environment], axis: [0, 1, 0], anchor: [0, 0, 2], "
        f"dynamics: {{damping: {damping}}}}}\n",
    )
    inertia = mass * (length**2 + 0.4 * r**2)
    gamma, omega = damping / (2 * inertia), math.sqrt(mass * G * length / inertia)
    assert gamma < omega / 2  # underdamped: several extremes to read
    pos = trace.bodies["bob"].pos
    theta = np.abs(np.arctan2(pos[:, 0], 2.0 - pos[:, 2]))
    extremes = [k for k in range(1, len(theta) - 1) if theta[k - 1] < theta[k] >= theta[k + 1]]
    assert len(extremes) >= 3
    tolerance = 2 * omega * h + theta0**2 / 8 + (duration / h) * _eps(engine)
    for k in extremes:
        truth = theta0 * math.exp(-gamma * float(trace.times[k]))
        assert abs(theta[k] - truth) <= tolerance * truth, (engine, float(trace.times[k]), float(theta[k]), truth)


NATIVE_DAMPING = [e for e in ENGINES if get_backend(e).native_damping]


@pytest.mark.parametrize("engine", NATIVE_DAMPING)
@pytest.mark.parametrize("kind", ["hinge", "slider"])
@pytest.mark.parametrize(
    ("mass", "radius", "damping", "h", "armature"),
    [
        (2.0, 0.2, 0.1, 0.001, 0.0),
        (0.5, 0.1, 0.2, 0.01, 0.0),
        (5.0, 0.3, 30.0, 0.004, 0.0),
        (1.0, 0.1, 0.05, 0.002, 0.02),
    ],
)
def test_implicit_damping_divides_the_rate_by_one_plus_c_h_over_i_each_step(
    tmp_path: Path, engine: str, kind: str, mass: float, radius: float, damping: float, h: float, armature: float
) -> None:
    v0, steps = 10.0, 50
    motion = f"angvel: [0, 0, {v0}]" if kind == "hinge" else f"vel: [0, 0, {v0}]"
    extra = f", armature: {armature}" if armature else ""
    trace = _run(
        tmp_path,
        engine,
        f"world: {{gravity: [0, 0, 0], dt: {h}, duration: {steps * h!r}}}\n"
        f"bodies:\n  wheel: {{cylinder: {{radius: {radius}, length: 0.05}}, mass: {mass}, pos: [0, 0, 1], {motion}}}\n"
        f"joints:\n  axle: {{type: {kind}, bodies: [wheel, environment], axis: [0, 0, 1], "
        f"dynamics: {{damping: {damping}{extra}}}}}\n",
    )
    inertia = (0.5 * mass * radius**2 if kind == "hinge" else mass) + armature
    n = np.rint(np.asarray(trace.joint_times) / h)
    assert n[-1] == steps
    rate = np.asarray(trace.joints["axle"].velocity, float)
    truth = v0 / (1.0 + h * damping / inertia) ** n
    assert np.all(np.abs(rate - truth) <= (n + 1) * _eps(engine) * v0 + 5e-10), (rate - truth).tolist()


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(("mass", "friction", "v0"), [(1.0, 2.0, 1.0), (5.0, 2.0, 2.0), (0.2, 0.5, 0.5)])
def test_friction_loss_stops_a_slider_at_v0_m_over_f(
    tmp_path: Path, engine: str, mass: float, friction: float, v0: float
) -> None:
    h = 0.001
    stop = v0 * mass / friction
    trace = _run(
        tmp_path,
        engine,
        f"world: {{gravity: [0, 0, {-G}], dt: {h}, duration: {stop + 0.5}}}\n"
        f"bodies:\n  cart: {{box: [0.2, 0.1, 0.1], mass: {mass}, pos: [0, 0, 1], vel: [{v0}, 0, 0]}}\n"
        "joints:\n  rail: {type: slider, bodies: [cart, environment], axis: [1, 0, 0], "
        f"dynamics: {{friction: {friction}}}}}\n",
    )
    x = trace.bodies["cart"].pos[:, 0]
    speed = trace.bodies["cart"].vel[:, 0]
    rounding = (stop / h) * _eps(engine) * v0  # the speed's rounding over the steps to the stop
    stopped = np.flatnonzero(np.abs(speed) <= 1e-6 * v0)
    assert stopped.size and abs(float(trace.times[stopped[0]]) - stop) <= 1.5 * h + rounding * mass / friction
    assert np.all(np.abs(speed[stopped[0] :]) <= 1e-6 * v0)  # held still by the friction afterwards
    distance = v0**2 * mass / (2 * friction)
    assert abs(float(x[-1]) - distance) <= v0 * h + rounding * stop, (engine, float(x[-1]), distance)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("mass", [1.0, 3.0])
def test_effort_limit_caps_a_motor_that_cannot_hold_its_load(tmp_path: Path, engine: str, mass: float) -> None:
    h, duration = 0.001, 0.5
    effort = 0.5 * mass * G
    trace = _run(
        tmp_path,
        engine,
        f"world: {{gravity: [0, 0, {-G}], dt: {h}, duration: {duration}}}\n"
        f"bodies:\n  load: {{box: [0.1, 0.1, 0.1], mass: {mass}, pos: [0, 0, 2]}}\n"
        "joints:\n  lift: {type: slider, bodies: [load, environment], axis: [0, 0, 1], "
        f"motor: {{vel: 0, fmax: {100 * mass * G}}}, dynamics: {{effort: {effort}}}}}\n",
    )
    a = G - effort / mass
    z = trace.bodies["load"].pos[:, 2]
    t = trace.times
    assert np.all(np.abs(z - (2.0 - 0.5 * a * t**2)) <= a * h * t / 2 + 1e-9 + 2.0 * _eps(engine) * t / h)
    force = trace.joints["lift"].motor_force[1:]
    assert np.all(np.abs(np.abs(force) - effort) <= 1e-5 * effort), (engine, force[:3])


@pytest.mark.parametrize("engine", ENGINES)
def test_velocity_limit_clamps_a_motors_commanded_rate(tmp_path: Path, engine: str) -> None:
    trace = _run(
        tmp_path,
        engine,
        f"world: {{gravity: [0, 0, {-G}], dt: 0.001, duration: 0.2}}\n"
        "bodies:\n  wheel: {cylinder: {radius: 0.2, length: 0.05}, mass: 2.0, pos: [0, 0, 1]}\n"
        "joints:\n  axle: {type: hinge, bodies: [wheel, environment], axis: [0, 0, 1], "
        "motor: {vel: 5, fmax: 1000}, dynamics: {velocity: 2}}\n",
    )
    assert abs(float(trace.joints["axle"].velocity[-1]) - 2.0) <= 1e-5 * 2.0


ARMATURE = (
    f"world: {{gravity: [0, 0, {-G}], dt: 0.001, duration: 1.0}}\n"
    "bodies:\n  wheel: {cylinder: {radius: 0.2, length: 0.05}, mass: 2.0, pos: [0, 0, 1], angvel: [0, 0, 10]}\n"
    "joints:\n  axle: {type: hinge, bodies: [wheel, environment], axis: [0, 0, 1], "
    "dynamics: {damping: 0.1, armature: 0.04}}\n"
)


@pytest.mark.parametrize("engine", ENGINES)
def test_armature_adds_to_the_inertia_where_declared_and_is_refused_elsewhere(tmp_path: Path, engine: str) -> None:
    if "joint:armature" not in {c.value for c in get_backend(engine).capabilities}:
        path = tmp_path / "s.yaml"
        path.write_text("schema_version: 1\nscenario: dynamics\n" + ARMATURE)
        with pytest.raises(UnsupportedFeature, match="joint:armature"):
            run_loaded(load_scenario(path), engine, tmp_path / engine)
        return
    trace = _run(tmp_path, engine, ARMATURE)
    inertia = 0.5 * 2.0 * 0.2**2 + 0.04  # the cylinder about its axis, plus the armature
    rate = trace.joints["axle"].velocity
    truth = 10.0 * np.exp(-0.1 * trace.joint_times / inertia)
    # the damping force uses the rate at the start of each step: (1 - c h / I)^n against e^(-c t / I)
    assert np.all(np.abs(rate - truth) <= 10.0 * (0.1 / inertia) ** 2 * 0.001 * trace.joint_times + 1e-9)
    world = build_program(load_scenario(tmp_path / "s.yaml")).world
    assert world.joints[0].dynamics.armature == 0.04
