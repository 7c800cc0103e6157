"""URDF `<mimic>` (capability `joint:mimic`) on every engine that declares it, refused up front elsewhere.

The model (tests/backends/models/mimic_pair.urdf): two arms on parallel hinges (axis y) from one fixed base,
horizontal at the zero configuration; `follow` mimics `lead` with multiplier m = -0.5 and offset c = 0.2 rad.
Released at rest under gravity, dt = h = 2 ms, T = 1 s. With the coupling rigid, the pair is one pendulum in
q = lead: J q'' = m_a g r_a cos q + m m_b g r_b cos(m q + c), J = I_a + m^2 I_b (I about each hinge). Every
engine here steps joint coordinates by semi-implicit Euler (PyBullet's Featherstone, MuJoCo's implicitfast
with no velocity-dependent force), so the reference is that method on the one-coordinate equation, same h.

Tolerances:

* the trace rounds positions to 1e-9 (docs/trace-format.md): 1e-9 on a difference of two readings;
* PyBullet: the gear is the solver's only row (no contact, no limit, the motors at fmax 0), which one
  Gauss-Seidel sweep solves exactly, and positions integrate the constrained rates: tracking within
  rounding, n eps |q| for n steps;
* DART: its coupler's row is the follower's rate alone; the backend solves each step for the offset that makes
  it the coupling's own row (backends/dart/_mimic.py) and keeps a step only when it leaves the follower within
  POSITION_TOLERANCE of its place; the next step's row removes that error in full (DART's coupler reduces
  errors at 1 per step), so the gap stays under that plus PyBullet's bound;
* MuJoCo: a joint equality is soft. With solref (-K, -B) = (-erp/h^2, -1/h) and impedance d, the constraint
  coordinate r obeys r'' = (1 - d) a0 - d B r' - d^2 K r, a0 its acceleration were it released (each arm a
  free pendulum: |a0| <= g (m_b r_b / I_b + |m| m_a r_a / I_a)): statically |r| = (1 - d) |a0| / (d^2 K), and
  at most twice that as it follows a0 (damping ratio d B / (2 d sqrt(K)) = 1.1, the discrete step at
  w h = sqrt(erp) = 0.45);
* Drake: its coupler constraint is SAP's near-rigid holonomic constraint (SapDriver: stiffness infinite,
  relaxation time h, beta 0.1): regularisation R = eps w with eps = beta^2 / (4 pi^2), and the impulse aims at
  removing the error g over h + relaxation time = 2h, so g' = g / 2 + eps (a0 h^2 + ...) per step settles below
  2 eps a0 h^2 / (1 - eps), monotonically from 0 (each joint is its own tree here: w is exact);
* ODE: a force pair (+u on the follower, -m u on the leader) solved for each step (backends/ode/_mimic.py); a
  kept step leaves the follower within its float32 tolerance of its place, the two angles' resolution
  4 eps32 max(1, |q|) each (the follower's, |m| times the leader's; |q| < 4 here), and reading the two float32
  angles adds as much again. ODE advances a body's
  quaternion by w h / 2 and renormalises, turning it by 2 atan(h w / 2) = h w - (h w)^3 / 12 + ...: with the
  rates held at v_f = m v_l the follower's angle misses m times the leader's by |m^3 - m| (h v)^3 / 12 in a
  step (the next step's error reduction 1 removes it: it does not add up), v at most sqrt(2 dV / J) with dV the
  largest drop of the two centres of mass (2 r each): 12.4 rad/s here;
* the leader: a follower off its place by r changes the torque on the leader by at most |m| m_b g r_b |r|,
  so q drifts by at most that / J x T^2 / 2 from the reference. ODE steps each arm as a free body held by the
  hinge's rows (maximal coordinates, ERP 0.2, CFM 1e-5, the quaternion step above), a first-order method other
  than the joint-space Euler of the reference (both O(h) from the truth): its own distance from the joint-space
  reference is taken from the same arm released without its coupling, on ODE in the same test.

The coupling's own size: the leader released alone falls to 0.593 rad at 0.2 s, coupled to 0.438 (the
reference); so a run ignoring the mimic fails both checks by orders of magnitude.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from backends.errors import UnsupportedFeature
from backends.registry import get_backend, is_installed
from reports.trace_reader import Trace, read_trace
from runner.language.load import load_scenario
from runner.sim.run import run_loaded
from tests.engines import INSTALLED

pytestmark = pytest.mark.slow
MODEL = Path(__file__).parent / "models" / "mimic_pair.urdf"
G, H, T = 9.81, 0.002, 1.0
M, C = -0.5, 0.2  # the file's multiplier and offset
MA, RA, IA = 1.0, 0.25, 0.02 + 1.0 * 0.25**2  # leader: mass, COM from the hinge, inertia about the hinge
MB, RB, IB = 0.5, 0.2, 0.01 + 0.5 * 0.2**2
J = IA + M * M * IB
ROUNDING = 1e-9
SCENARIO = f"""schema_version: 1
scenario: mimic-pair
world: {{gravity: [0, 0, {-G}], dt: {H}, duration: {T}}}
bodies:
  ground: {{plane: {{}}, motion: static, pos: [0, 0, -1]}}
robots:
  r:
    urdf: mimic_pair.urdf
    pos: [0, 0, 1]
    fixed: true
"""


def _reference() -> np.ndarray:
    """The leader at every step: semi-implicit Euler on the one-coordinate equation (module docstring)."""
    q, v, out = 0.0, 0.0, [0.0]
    for _ in range(round(T / H)):
        v += H * (MA * G * RA * math.cos(q) + M * MB * G * RB * math.cos(M * q + C)) / J
        q += H * v
        out.append(q)
    return np.array(out)


def _declares(engine: str) -> bool:
    from backends.types import Capability

    return Capability.JOINT_MIMIC in get_backend(engine).capabilities


def _run(tmp_path: Path, engine: str) -> Trace:
    (tmp_path / "mimic_pair.urdf").write_bytes(MODEL.read_bytes())
    (tmp_path / "pair.yaml").write_text(SCENARIO)
    result = run_loaded(load_scenario(tmp_path / "pair.yaml"), engine, tmp_path / engine)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    return read_trace(result.trace)


def _tracking_bound(engine: str, a0: float, vmax: float, magnitude: float, multiplier: float = M) -> float:
    """How far the follower may be from ``multiplier`` x leader + offset (module docstring): ``a0`` the coupling
    coordinate's acceleration were it released, ``vmax`` the leader's largest rate, ``magnitude`` the largest
    |q| of either joint."""
    steps = round(T / H)
    if engine == "ode":
        from backends.ode._mimic import EPS32, HINGE_RESOLUTION

        held = HINGE_RESOLUTION * EPS32 * (1.0 + abs(multiplier)) * max(1.0, magnitude)  # a kept step's tolerance
        return ROUNDING + 2.0 * held + abs(multiplier**3 - multiplier) * (H * vmax) ** 3 / 12.0
    bound = ROUNDING + steps * get_backend(engine).precision.eps * magnitude
    if engine == "mujoco":
        from backends.mujoco._geoms import IMPEDANCE
        from backends.mujoco._options import MujocoOptions

        d, stiffness = IMPEDANCE, MujocoOptions().erp / H**2
        bound += 2.0 * (1.0 - d) * a0 / (d * d * stiffness)
    if engine == "drake":
        eps = 0.1**2 / (4 * math.pi**2)
        bound += 2.0 * eps / (1.0 - eps) * a0 * H**2
    if engine == "dart":
        from backends.dart._mimic import POSITION_TOLERANCE

        bound += POSITION_TOLERANCE
    return bound


def _free_acceleration() -> float:
    """|a0|: the coupling coordinate's acceleration were it released (each arm a free pendulum)."""
    return G * (MB * RB / IB + abs(M) * MA * RA / IA)


def _fastest() -> float:
    """The leader's largest rate: sqrt(2 dV / J), dV the largest drop of both centres of mass (2 r each)."""
    return math.sqrt(2.0 * G * (MA * 2 * RA + MB * 2 * RB) / J)


def _maximal_coordinates_gap(tmp_path: Path, engine: str) -> float:
    """ODE only (module docstring): the leader released without its coupling, against the joint-space Euler
    reference of that one pendulum (J = I_a, torque m_a g r_a cos q)."""
    if engine != "ode":
        return 0.0
    alone = tmp_path / "alone"
    alone.mkdir()
    (alone / "mimic_pair.urdf").write_text(MODEL.read_text().replace('<mimic joint="lead" multiplier="-0.5" '
                                                                    'offset="0.2"/>', ""))
    (alone / "pair.yaml").write_text(SCENARIO)
    result = run_loaded(load_scenario(alone / "pair.yaml"), engine, alone / engine)
    assert result.status == "passed" and result.trace is not None, result.failure
    lead = read_trace(result.trace).joints["r.lead"].position
    q, v, out = 0.0, 0.0, [0.0]
    for _ in range(round(T / H)):
        v += H * MA * G * RA * math.cos(q) / IA
        q += H * v
        out.append(q)
    return float(np.max(np.abs(lead - np.array(out)[: len(lead)])))


@pytest.mark.parametrize("engine", [e for e in INSTALLED if _declares(e)])
def test_a_mimic_joint_follows_its_leader(tmp_path: Path, engine: str) -> None:
    trace = _run(tmp_path, engine)
    lead, follow = trace.joints["r.lead"].position, trace.joints["r.follow"].position
    assert lead[0] == 0.0 and follow[0] == pytest.approx(C, abs=ROUNDING)  # started where its leader puts it
    track = _tracking_bound(engine, _free_acceleration(), _fastest(), 4.0)  # |q| < 4 rad over the run
    gap = float(np.max(np.abs(follow - (M * lead + C))))
    assert gap <= track, (engine, gap, track)
    reference = _reference()
    drift = abs(M) * MB * G * RB * (track - ROUNDING) / J * T * T / 2 + 2 * ROUNDING
    drift += _maximal_coordinates_gap(tmp_path, engine)
    off = float(np.max(np.abs(lead - reference[: len(lead)])))
    assert off <= drift, (engine, off, drift)
    assert float(np.ptp(lead)) > 2.0  # it swung through most of a half turn: not a still comparison


AXES = Path(__file__).parent / "models" / "mimic_axes.urdf"
GEAR, TAU = 2.0, 0.06  # mimic_axes.urdf's multiplier; the torque on the leader (N m)
IA_AXIS, IB_AXIS = 0.02, 0.01  # each wheel's inertia about its own hinge, through its centre of mass
J_AXIS = IA_AXIS + GEAR**2 * IB_AXIS  # 0.06 kg m^2: the leader turns at TAU / J_AXIS = 1 rad/s^2
AXES_SCENARIO = f"""schema_version: 1
scenario: mimic-axes
world: {{gravity: [0, 0, 0], dt: {H}, duration: {T}}}
robots:
  r:
    urdf: mimic_axes.urdf
    fixed: true
    joints:
      lead: {{drive: {{torque: {TAU}}}}}
"""


@pytest.mark.parametrize("engine", [e for e in INSTALLED if _declares(e)])
def test_a_torque_on_the_leader_turns_both_at_tau_over_the_coupled_inertia(tmp_path: Path, engine: str) -> None:
    """Two wheels on parallel hinges through their centres of mass, no gravity: `follow` = 2 x `lead`, a torque
    tau on `lead`. The coupling's force pair (+u on the follower, -m u on the leader) does not change the
    momentum P = I_a v_l + m I_b v_f, so P = tau t whatever u (a coupling that pushed only the follower, or
    were not two-way, breaks it); with the coupling held, the leader turns at tau / (I_a + m^2 I_b) (1 rad/s^2,
    against 3 alone). Each wheel turns about a principal axis through its centre of mass: no centripetal,
    gyroscopic or constraint term, so every engine's step is joint-space semi-implicit Euler, v_n = n h a and
    q_n = h^2 a n (n + 1) / 2. Tolerances: P from the trace's rates (1e-9 each) and n eps of the largest
    momentum for n steps of rounding; the leader moves by -(m I_b / J) times the follower's miss of its place
    (J q_l = sum of h P - m I_b (q_f - m q_l)), that miss bounded as in the gravity test (its a0: |m| tau / I_a,
    the follower free), plus n eps |q| of rounding and on ODE the quaternion step's deficit (h w)^3 / 12 a step
    on the leader's own angle (module docstring)."""
    (tmp_path / "mimic_axes.urdf").write_bytes(AXES.read_bytes())
    (tmp_path / "axes.yaml").write_text(AXES_SCENARIO)
    result = run_loaded(load_scenario(tmp_path / "axes.yaml"), engine, tmp_path / engine)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    trace = read_trace(result.trace)
    lead, follow = trace.joints["r.lead"], trace.joints["r.follow"]
    steps, eps, a = round(T / H), get_backend(engine).precision.eps, TAU / J_AXIS
    n = np.arange(len(lead.position))
    time = n * H
    momentum = IA_AXIS * lead.velocity + GEAR * IB_AXIS * follow.velocity
    largest = TAU * T
    assert float(np.max(np.abs(momentum - TAU * time))) <= ROUNDING * (IA_AXIS + GEAR * IB_AXIS) + steps * eps * largest
    vmax, qmax = a * T, GEAR * a * T * T  # the follower's angle: m a T^2 / 2 at most, within 2x
    track = _tracking_bound(engine, GEAR * TAU / IA_AXIS, vmax, qmax, GEAR)
    assert float(np.max(np.abs(follow.position - GEAR * lead.position))) <= track
    reference = H * H * a * n * (n + 1) / 2
    bound = GEAR * IB_AXIS / J_AXIS * track + ROUNDING + steps * eps * max(1.0, qmax)
    if engine == "ode":
        bound += steps * (H * vmax) ** 3 / 12.0
    off = float(np.max(np.abs(lead.position - reference)))
    assert off <= bound, (engine, off, bound)
    assert reference[-1] == pytest.approx(0.5 * a * T * T, rel=2 * H / T)  # 0.5 rad: against 1.5 alone


#: every installed engine now declares joint:mimic; the runner's fake backend stands for one that does not
WITHOUT_MIMIC = [*(e for e in INSTALLED if not _declares(e)), "fake"]


@pytest.mark.parametrize("engine", WITHOUT_MIMIC)
def test_an_engine_without_mimic_refuses_it_up_front(tmp_path: Path, engine: str) -> None:
    (tmp_path / "mimic_pair.urdf").write_bytes(MODEL.read_bytes())
    (tmp_path / "pair.yaml").write_text(SCENARIO)
    with pytest.raises(UnsupportedFeature, match=rf"joint:mimic.*`{engine}`"):
        run_loaded(load_scenario(tmp_path / "pair.yaml"), engine, tmp_path / engine)


#: what each engine that refuses several couplings in one joint tree says (the engine's _mimic module docstring)
SHARED_TREE_REFUSALS = {
    "dart": r"`dart` holds one joint:mimic per joint tree: `arm\.\w+` and",
    "ode": r"`ode` holds one joint:mimic per group of jointed bodies: `arm\.\w+` and",
}


@pytest.mark.parametrize("engine", [e for e in SHARED_TREE_REFUSALS if e in INSTALLED])
@pytest.mark.skipif(not is_installed("pybullet"), reason="pybullet_data")
def test_several_mimics_in_one_tree_are_refused_up_front(tmp_path: Path, engine: str) -> None:
    """xarm6_with_gripper: five fingers mimic one joint. DART's coupler rows of one tree share an LCP whose
    matrix is not symmetric (row: the follower's rate; impulse: on both joints), which its solver leaves
    unsolved (docs/backends/dart.md, "Mimic joints"); on ODE the force pairs' trial steps made ODE abort
    (docs/backends/ode.md, "Mimic joints"): refused before the run, naming both joints."""
    (tmp_path / "xarm.yaml").write_text(
        """schema_version: 1
scenario: xarm
world: {gravity: [0, 0, -9.81], dt: 0.002, duration: 0.1}
robots:
  arm: {urdf: "@pybullet_data/xarm/xarm6_with_gripper.urdf", fixed: true}
"""
    )
    with pytest.raises(UnsupportedFeature, match=SHARED_TREE_REFUSALS[engine]):
        run_loaded(load_scenario(tmp_path / "xarm.yaml"), engine, tmp_path / "out")


@pytest.mark.skipif(not is_installed("pybullet"), reason="pybullet_data ships with pybullet")
def test_franka_pandas_second_finger_mimics_the_first(tmp_path: Path) -> None:
    """pybullet_data's Franka Panda: `panda_finger_joint2` mimics `panda_finger_joint1` (multiplier 1, no
    offset). A servo opens finger 1 to 0.03 m; finger 2 follows it. Here the gear shares Bullet's solve with
    the servos' and the stops' rows, which Gauss-Seidel does not solve exactly: if a step leaves at most the
    step's own relative motion uncorrected (no worse than no gear), and the gear's ERP removes the fraction
    E = 1 x 0.2 (its erp times Bullet's multibody erp, 0.2 by default) of the error each step, the error
    stays below max|dq1| / E. Ignoring the mimic leaves finger 2 at 0, 0.03 m off."""
    (tmp_path / "panda.yaml").write_text(
        """schema_version: 1
scenario: panda-fingers
world: {gravity: [0, 0, -9.81], dt: 0.002, duration: 0.5}
bodies:
  ground: {plane: {}, motion: static}
robots:
  arm:
    urdf: "@pybullet_data/franka_panda/panda.urdf"
    fixed: true
    joints:
      panda_finger_joint1: {servo: {target: 0.03, gain: 20, fmax: 20}}
"""
    )
    held = "".join(f"      panda_joint{k}: {{servo: {{target: 0, gain: 20, fmax: 300}}}}\n" for k in range(1, 8))
    (tmp_path / "panda.yaml").write_text((tmp_path / "panda.yaml").read_text() + held)  # only the fingers move
    result = run_loaded(load_scenario(tmp_path / "panda.yaml"), "pybullet", tmp_path / "out")
    assert result.status == "passed", result.failure
    assert result.trace is not None
    trace = read_trace(result.trace)
    one, two = trace.joints["arm.panda_finger_joint1"].position, trace.joints["arm.panda_finger_joint2"].position
    assert one[-1] == pytest.approx(0.03, abs=1e-3)  # the servo opened it (its own tolerance: not this test's)
    bound = float(np.max(np.abs(np.diff(one)))) / (1.0 * 0.2) + ROUNDING
    assert float(np.max(np.abs(two - one))) <= bound
