"""MuJoCo's inertia-box fluid model (MJCF `<option density viscosity wind>`) on every engine: MuJoCo runs it from the
file, the others get the runner's forces before each step (runner.sim.fluid; docs/semantics.md, "Fluid forces").
Each case is an MJCF file with one moving body, no contact, against the analytic solution and against MuJoCo's own
`mj_step` on the same file.

**Box and sphere.** A body of mass m with principal moments I_i is a box of sides d_i = sqrt(6 (I_j + I_k - I_i) /
m): a box geom's own sides, and for a sphere of radius r (I = 2 m r^2 / 5) d = r sqrt(2.4) on each axis.

**Terminal velocity.** Falling under g in a viscous fluid (viscosity b only), m v' = m g - 3 pi b d v: the terminal
speed is v* = m g / (3 pi b d). With density p only, m v' = m g - p d^2 v^2 / 2: v* = sqrt(2 m g / (p d^2)). A wind
w with viscosity only and no gravity: v -> w. Every engine's step here is semi-implicit Euler with the force taken
at the step's start (v_{n+1} = v_n + h f(v_n) / m): it has the same fixed point v*, and the error e_n = v* - v_n
shrinks by the factor (1 - h c) per step, c = 3 pi b d / m (viscous: exactly), c = p d^2 v* / (2 m) (quadratic:
e_{n+1} = e_n (1 - h k (v* + v_n)), k = p d^2 / (2 m), v_n in [0, v*]). MuJoCo's backend with the scenario's
options steps with implicitfast, which also divides by (1 + h D), D the drag's derivative (3 pi b d / m, or 2 k v_n
<= 2 k v*): factor 1 / (1 + h c), or 1 - h k v* / (1 + 2 h k v*). The bound after n steps is v* times the largest
of these factors to the n, plus rounding.

**Spin decay.** A box spinning on a hinge about its principal z axis through its centre, no gravity: I w' = -a w -
q w^2 with a = pi b d^3 (d the mean side) and q = p d_z (d_x^4 + d_y^4) / 64, so w(t) = A w0 e^(-A t) / (A + Q w0
(1 - e^(-A t))), A = a / I, Q = q / I. One Euler step (explicit, or implicitfast's) errs by h^2 w''(t) / 2 to
second order, and w'' = (A + 2 Q w)(A w + Q w^2) > 0 falls as w does; the error of earlier steps only shrinks
(factor 1 - h (A + 2 Q w) in (0, 1)). Summed: |w_n - w(t_n)| <= h (|w'(0)| + h w''(0)) / 2, with (1 + h (A + 2 Q
w0)) for implicitfast's third-order term.

**Against MuJoCo's mj_step.** The same file stepped by `mujoco.mj_step` with the Euler integrator (for the mujoco
backend with the scenario's options: implicitfast, which that backend uses; with `options: model`: the file's own,
Euler): the same discrete map, so the two agree to rounding, 8 n eps (|v| + 1) after n steps in the engine's
precision (each step rounds the velocity and the force; the map contracts, so earlier roundings do not grow), plus
the trace's own rounding to 1e-9. This also shows the runner does not add the fluid a second time on MuJoCo: that
would halve v*.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from backends.errors import UnsupportedFeature
from backends.registry import KNOWN_BACKENDS, check_capabilities, get_backend, is_installed
from backends.types import BodyStates
from reports.trace_reader import read_trace
from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.sim.fluid import FluidForces
from runner.sim.run import run_loaded

mujoco = pytest.importorskip("mujoco", reason="engine not installed: pip install 'physics-scenarios[mujoco]'")

pytestmark = pytest.mark.slow
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in) and is_installed(n)]
H, G = 0.002, 9.81
M, R = 0.2, 0.05  # the ball: kg, m
D_BALL = R * math.sqrt(2.4)  # its box side (module docstring)
SIDES, M_BOX, W0 = (0.2, 0.1, 0.05), 1.0, 20.0  # the spinning box: full sides (m), kg, rad/s
TRACE_ROUNDING = 0.5e-9  # the trace keeps every per-step double rounded to 1e-9 (runner/trace)
RUNS = [(e, "scenario") for e in ENGINES] + [("mujoco", "model")] * ("mujoco" in ENGINES)

BALL = """<mujoco>
  <option timestep="{h}" gravity="{g}" viscosity="{viscosity}" density="{density}" wind="{wind}"/>
  <worldbody>
    <body name="ball" pos="0 0 1">
      <freejoint/>
      <geom type="sphere" size="{r}" mass="{m}" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""
BOX = """<mujoco>
  <option timestep="{h}" gravity="0 0 0" viscosity="{viscosity}" density="{density}"/>
  <worldbody>
    <body name="box" pos="0 0 1">
      <joint name="spin" type="hinge" axis="0 0 1"/>
      <geom type="box" size="{sx} {sy} {sz}" mass="{m}" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def _run(tmp_path: Path, xml: str, engine: str, options: str, duration: float, spin: float = 0.0
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """(times, the body's linear velocity, its angular velocity) from the runner's trace."""
    (tmp_path / "fluid.xml").write_text(xml)
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "fluid.xml"))
    g = [float(c) for c in model.opt.gravity]
    initial = f", initial: {{joints: {{spin: {{pos: 0, vel: {spin}}}}}}}" if spin else ""
    (tmp_path / "s.yaml").write_text(
        f"schema_version: 1\nscenario: fluid\nworld: {{dt: {H}, duration: {duration}, gravity: {g}, "
        f"options: {options}}}\nrobots:\n  r: {{mjcf: fluid.xml{initial}}}\n"
    )
    result = run_loaded(load_scenario(tmp_path / "s.yaml", None), engine, tmp_path / f"out-{engine}-{options}")
    assert result.status == "passed", result
    assert result.trace is not None
    trace = read_trace(result.trace)
    body = next(b for name, b in trace.bodies.items() if name != "r.worldbody")
    return trace.times, body.vel, body.angvel


def _reference(tmp_path: Path, steps: int, implicit: bool, spin: float = 0.0) -> np.ndarray:
    """MuJoCo's own mj_step on the same file: the ball's world linear velocity (its free joint's first three
    rates), or the box's hinge rate (``spin``: its start), after each step, the start first."""
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "fluid.xml"))
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST if implicit else mujoco.mjtIntegrator.mjINT_EULER
    data = mujoco.MjData(model)
    data.qvel[0] = spin
    out = [data.qvel[:3].copy()]
    for _ in range(steps):
        mujoco.mj_step(model, data)
        out.append(data.qvel[:3].copy())
    return np.array(out)


def _implicit(engine: str, options: str) -> bool:
    return engine == "mujoco" and options == "scenario"  # the mujoco backend's own integrator (backends/mujoco)


def _rounding(engine: str, steps: int, scale: float) -> float:
    return 8 * steps * get_backend(engine).precision.eps * (scale + 1.0) + TRACE_ROUNDING


def _check_mj_step(tmp_path: Path, engine: str, options: str, vel: np.ndarray, angular: bool,
                   spin: float = 0.0) -> None:  # fmt: skip
    steps = len(vel) - 1
    ref = _reference(tmp_path, steps, _implicit(engine, options), spin)
    if angular:
        vel, ref = vel[:, 2], ref[:, 0]
    gap = float(np.max(np.abs(vel - ref)))
    assert gap <= _rounding(engine, steps, float(np.max(np.abs(ref)))), (engine, options, gap)


@pytest.mark.parametrize(("engine", "options"), RUNS)
def test_a_ball_sinks_at_the_viscous_terminal_velocity(tmp_path: Path, engine: str, options: str) -> None:
    viscosity, duration = 5.0, 1.0
    xml = BALL.format(h=H, g=f"0 0 {-G}", viscosity=viscosity, density=0, wind="0 0 0", r=R, m=M)
    times, vel, _ = _run(tmp_path, xml, engine, options, duration)
    c = 3 * math.pi * viscosity * D_BALL / M
    terminal = M * G / (3 * math.pi * viscosity * D_BALL)
    steps = len(times) - 1
    bound = terminal * (1 / (1 + H * c)) ** steps + _rounding(engine, steps, terminal)
    assert abs(-vel[-1, 2] - terminal) <= bound, (engine, float(vel[-1, 2]), terminal, bound)
    assert np.all(np.abs(vel[:, :2]) <= _rounding(engine, steps, terminal))  # straight down
    _check_mj_step(tmp_path, engine, options, vel, angular=False)


@pytest.mark.parametrize(("engine", "options"), RUNS)
def test_a_ball_falls_at_the_quadratic_terminal_velocity(tmp_path: Path, engine: str, options: str) -> None:
    density, duration = 1000.0, 1.0
    xml = BALL.format(h=H, g=f"0 0 {-G}", viscosity=0, density=density, wind="0 0 0", r=R, m=M)
    times, vel, _ = _run(tmp_path, xml, engine, options, duration)
    terminal = math.sqrt(2 * M * G / (density * D_BALL**2))
    hkv = H * density * D_BALL**2 / (2 * M) * terminal
    steps = len(times) - 1
    bound = terminal * (1 - hkv / (1 + 2 * hkv)) ** steps + _rounding(engine, steps, terminal)
    assert abs(-vel[-1, 2] - terminal) <= bound, (engine, float(vel[-1, 2]), terminal, bound)
    _check_mj_step(tmp_path, engine, options, vel, angular=False)


@pytest.mark.parametrize(("engine", "options"), RUNS)
def test_a_ball_at_rest_is_carried_at_the_winds_speed(tmp_path: Path, engine: str, options: str) -> None:
    viscosity, wind, duration = 5.0, (0.3, -0.2, 0.0), 1.0
    xml = BALL.format(h=H, g="0 0 0", viscosity=viscosity, density=0, wind=" ".join(map(str, wind)), r=R, m=M)
    times, vel, _ = _run(tmp_path, xml, engine, options, duration)
    c = 3 * math.pi * viscosity * D_BALL / M
    steps = len(times) - 1
    speed = math.hypot(*wind)
    bound = speed * (1 / (1 + H * c)) ** steps + _rounding(engine, steps, speed)
    assert np.all(np.abs(vel[-1] - np.array(wind)) <= bound), (engine, vel[-1].tolist(), bound)
    _check_mj_step(tmp_path, engine, options, vel, angular=False)


@pytest.mark.parametrize(("engine", "options"), RUNS)
def test_a_spinning_box_slows_down_as_the_fluid_drags_it(tmp_path: Path, engine: str, options: str) -> None:
    viscosity, density, duration = 0.5, 1000.0, 0.5
    sx, sy, sz = SIDES
    xml = BOX.format(h=H, viscosity=viscosity, density=density, sx=sx / 2, sy=sy / 2, sz=sz / 2, m=M_BOX)
    times, _, angvel = _run(tmp_path, xml, engine, options, duration, spin=W0)
    inertia = M_BOX * (sx**2 + sy**2) / 12
    mean = (sx + sy + sz) / 3
    a = math.pi * viscosity * mean**3 / inertia
    q = density * sz * (sx**4 + sy**4) / 64 / inertia
    decay = np.exp(-a * times)
    exact = a * W0 * decay / (a + q * W0 * (1 - decay))
    rate, curvature = a * W0 + q * W0**2, (a + 2 * q * W0) * (a * W0 + q * W0**2)
    steps = len(times) - 1
    bound = H * (rate + H * curvature) / 2 * (1 + H * (a + 2 * q * W0)) + _rounding(engine, steps, W0)
    gap = float(np.max(np.abs(angvel[:, 2] - exact)))
    assert gap <= bound, (engine, gap, bound)
    assert angvel[-1, 2] < 0.5 * W0  # it did slow down (w(0.5 s) = 3.3 rad/s)
    _check_mj_step(tmp_path, engine, options, angvel, angular=True, spin=W0)


def _trace(tmp_path: Path, text: str, engine: str, body: str) -> tuple[np.ndarray, np.ndarray]:
    (tmp_path / "own.yaml").write_text(text)
    result = run_loaded(load_scenario(tmp_path / "own.yaml", None), engine, tmp_path / f"own-{engine}")
    assert result.status == "passed" and result.trace is not None, result
    trace = read_trace(result.trace)
    return trace.times, trace.bodies[body].vel


@pytest.mark.parametrize("engine", ENGINES)
def test_the_scenarios_fluid_drags_its_own_bodies(tmp_path: Path, engine: str) -> None:
    """`world.fluid` without any model: a hand-written ball (ODE's sphere inertia, 2 m r^2 / 5, the MJCF ball's)
    sinks at the viscous terminal velocity, as above; MuJoCo gets the fluid as its `<option>`."""
    viscosity = 5.0
    times, vel = _trace(tmp_path, f"schema_version: 1\nscenario: own\nworld: {{dt: {H}, duration: 1.0, gravity: "
                        f"[0, 0, {-G}], fluid: {{viscosity: {viscosity}}}}}\n"
                        f"bodies:\n  ball: {{sphere: {R}, mass: {M}, pos: [0, 0, 1]}}\n", engine, "ball")  # fmt: skip
    c = 3 * math.pi * viscosity * D_BALL / M
    terminal = M * G / (3 * math.pi * viscosity * D_BALL)
    steps = len(times) - 1
    bound = terminal * (1 / (1 + H * c)) ** steps + _rounding(engine, steps, terminal)
    assert abs(-vel[-1, 2] - terminal) <= bound, (engine, float(vel[-1, 2]), terminal, bound)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_still_fluid_in_the_scenario_replaces_the_files(tmp_path: Path, engine: str) -> None:
    """`world.fluid: {}` (no density, no viscosity) over the MJCF ball's viscous `<option>`: no drag on any engine
    (MuJoCo's option zeroed too), so the ball falls freely, v_n = -g n h in a semi-implicit Euler step."""
    (tmp_path / "fluid.xml").write_text(BALL.format(h=H, g=f"0 0 {-G}", viscosity=5.0, density=0, wind="0 0 0",
                                                    r=R, m=M))  # fmt: skip
    text = (f"schema_version: 1\nscenario: own\nworld: {{dt: {H}, duration: 0.2, gravity: [0, 0, {-G}], fluid: {{}}}}\n"
            "robots:\n  r: {mjcf: fluid.xml}\n")  # fmt: skip
    times, vel = _trace(tmp_path, text, engine, "r.ball")
    steps = len(times) - 1
    assert np.all(np.abs(vel[:, 2] + G * times) <= _rounding(engine, steps, G * times[-1])), engine


def test_the_models_own_options_take_no_fluid_from_the_scenario(tmp_path: Path) -> None:
    (tmp_path / "fluid.xml").write_text(BALL.format(h=H, g=f"0 0 {-G}", viscosity=5.0, density=0, wind="0 0 0",
                                                    r=R, m=M))  # fmt: skip
    (tmp_path / "own.yaml").write_text(f"schema_version: 1\nscenario: own\nworld: {{dt: {H}, duration: 0.2, gravity: "
                                       f"[0, 0, {-G}], options: model, fluid: {{viscosity: 1}}}}\n"
                                       "robots:\n  r: {mjcf: fluid.xml}\n")  # fmt: skip
    with pytest.raises(ScenarioValidationError, match=r"own.yaml:3:\d+: world.fluid: with `options: model` the fluid"):
        load_scenario(tmp_path / "own.yaml", None)


def test_the_runners_wrench_is_mujocos_passive_force(tmp_path: Path) -> None:
    """One body with its centre of mass off its frame and its principal axes turned (two geoms), moving and
    turning in all directions in a fluid with density, viscosity and wind: the runner's force at the centre
    of mass and torque (runner.sim.fluid, from the description the engines get) are MuJoCo's own
    `qfrc_passive` for the same state (the free joint's force, and its torque about the body's origin in the
    body's axes), to rounding (1e-12 of the largest component: the same few dozen double operations in another
    order): the formulas, the box, the axes and the wind are MuJoCo's. The moments are
    distinct, so the principal axes are the same up to order and sign whichever way they are found."""
    (tmp_path / "fluid.xml").write_text("""<mujoco>
  <option density="800" viscosity="0.3" wind="0.4 -1.1 0.25"/>
  <worldbody>
    <body name="b" pos="0.1 0.2 1" euler="10 20 30">
      <freejoint/>
      <geom type="box" size="0.2 0.05 0.03" pos="0.05 0.02 0" euler="0 0 25" mass="2" contype="0" conaffinity="0"/>
      <geom type="capsule" fromto="0 0 0 0.1 0.1 0.2" size="0.03" mass="0.7" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
""")
    (tmp_path / "s.yaml").write_text("schema_version: 1\nscenario: wrench\nworld: {dt: 0.002, duration: 0.01}\n"
                                     "robots:\n  r: {mjcf: fluid.xml}\n")  # fmt: skip
    world = build_program(load_scenario(tmp_path / "s.yaml", None)).world
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "fluid.xml"))
    data = mujoco.MjData(model)
    data.qvel[:] = [0.7, -0.4, 1.3, 2.1, -3.2, 1.7]  # the origin's velocity (world), the angular one (body axes)
    mujoco.mj_forward(model, data)
    rot = data.xmat[1].reshape(3, 3)
    index = world.body_index("r.b")
    rows = np.zeros((len(world.bodies), 13))
    rows[:, 3] = 1.0
    rows[index] = [*data.xpos[1], *data.xquat[1], *data.qvel[:3], *(rot @ data.qvel[3:])]
    fluid = FluidForces(world, native=False)
    assert fluid.bodies.tolist() == [index]
    forces, torques = fluid.wrenches(BodyStates.from_rows(rows))
    arm = data.xipos[1] - data.xpos[1]  # the centre of mass from the body's origin, world
    torque_origin = rot.T @ (torques[0] + np.cross(arm, forces[0]))
    scale = float(np.max(np.abs(data.qfrc_passive)))
    assert np.allclose(forces[0], data.qfrc_passive[:3], rtol=0, atol=1e-12 * scale), (forces[0], data.qfrc_passive)
    assert np.allclose(torque_origin, data.qfrc_passive[3:], rtol=0, atol=1e-12 * scale), data.qfrc_passive


@pytest.mark.parametrize("engine", ENGINES)
def test_the_per_geom_ellipsoid_model_is_mujocos_alone(tmp_path: Path, engine: str) -> None:
    """A geom's `fluidshape="ellipsoid"` (MuJoCo's per-geom model, not the inertia box) is refused before the run
    on every engine but MuJoCo, naming the capability, the geom and its line."""
    (tmp_path / "fluid.xml").write_text(BALL.format(h=H, g=f"0 0 {-G}", viscosity=5.0, density=0, wind="0 0 0", r=R,
                                                    m=M).replace('<geom type="sphere"', '<geom name="shell" '
                                                                 'fluidshape="ellipsoid" type="sphere"'))  # fmt: skip
    (tmp_path / "s.yaml").write_text(f"schema_version: 1\nscenario: ellipsoid\nworld: {{dt: {H}, duration: 0.01}}\n"
                                     "robots:\n  r: {mjcf: fluid.xml}\n")  # fmt: skip
    world = build_program(load_scenario(tmp_path / "s.yaml", None)).world
    if engine == "mujoco":
        check_capabilities(get_backend(engine), world)
        return
    with pytest.raises(UnsupportedFeature, match=r"world:fluid-ellipsoid .*fluid.xml:6: geom `shell` of body `ball`"):
        check_capabilities(get_backend(engine), world)
