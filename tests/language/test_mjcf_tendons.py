"""MJCF tendons and equalities on every engine (issue 28, item 2; runner.language.mjcf_needs).

A tendon without a force of its own is inert (accepted everywhere, noted); one that acts stays
`constraint:tendon`. An equality that reduces to a linear relation between two hinges or slides is a mimic
joint (`joint:mimic`); every other stays `constraint:equality`. The derivation of a mimic's multiplier and
offset is checked against MuJoCo's own equality residual (``efc_pos``), and a coupled pair runs on PyBullet and
Drake against `mujoco.mj_step` on the same file.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from backends.registry import get_backend
from backends.types import Capability
from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from runner.language.mjcf import load_mjcf
from runner.language.robot_desc import MimicDesc
from runner.sim.run import run_loaded
from tests.backends import test_mimic as mimic_tests
from tests.engines import INSTALLED
from tests.paths import ROOT

mujoco = pytest.importorskip("mujoco", reason="reading MJCF needs MuJoCo's compiler (the `mujoco` extra)")
dm_control = pytest.importorskip("dm_control", reason="dm_control's suite is a test dependency (dm-control)")
SUITE = Path(dm_control.__file__).parent / "suite"
PYBULLET_MJCF = Path(__import__("pybullet_data").getDataPath()) / "mjcf"
TENDON, EQUALITY = "constraint:tendon", "constraint:equality"

#: The survey's files with a `<tendon>` or an `<equality>`, unmodified: before, each needed constraint:tendon
#: (and manipulator, quadruped, stacker constraint:equality too), so only MuJoCo ran them. Now: what they still
#: need of the two, the mimics they hold, and what names the refusal.
CORPUS = {
    PYBULLET_MJCF / "humanoid_fixed.xml": (set(), {}),  # left_hipknee, right_hipknee: no force, unused
    PYBULLET_MJCF / "humanoid_symmetric.xml": (set(), {}),
    PYBULLET_MJCF / "humanoid_symmetric_no_ground.xml": (set(), {}),
    SUITE / "dog.xml": (set(), {}),  # 8 tendons, each an actuator's transmission only
    SUITE / "point_mass.xml": (set(), {}),
    SUITE / "manipulator.xml": (set(), {"finger": MimicDesc("thumb", 1.0, 0.0)}),  # -0.5 thumb + 0.5 finger = 0
    SUITE / "stacker.xml": (set(), {"finger": MimicDesc("thumb", 1.0, 0.0)}),
    SUITE / "quadruped.xml": ({EQUALITY}, {}),  # pitch + knee + ankle held at 0: a coupling of three joints
    SUITE / "ball_in_cup.xml": ({TENDON}, {}),  # the string: a spatial tendon's length limit
    SUITE / "fish.xml": ({TENDON}, {}),  # fins_sym's stiffness 1e-4
}


def _line(file: Path, text: str) -> int:
    return next(k for k, line in enumerate(file.read_text().splitlines(), 1) if text in line)


@pytest.mark.parametrize("file", list(CORPUS), ids=lambda f: f.stem)
def test_the_corpus_needs_only_what_acts(file: Path) -> None:
    desc = load_mjcf(file)
    needs, mimics = CORPUS[file]
    assert {n.capability for n in desc.needs} & {TENDON, EQUALITY} == needs
    assert {j.name: j.mimic for j in desc.joints if j.mimic is not None} == mimics
    m = mujoco.MjModel.from_xml_path(str(file)) if "humanoid" not in file.stem else None
    if m is not None and TENDON not in needs:  # every tendon is named in the note, with what uses it
        note = next(n for n in desc.notes if n.startswith("tendons without a force"))
        assert all(f"`{m.tendon(t).name}`" in note for t in range(m.ntendon))


def test_an_acting_tendon_and_a_coupling_of_three_are_named_at_their_lines() -> None:
    cup = {n.capability: n for n in load_mjcf(SUITE / "ball_in_cup.xml").needs}[TENDON]
    string = _line(SUITE / "ball_in_cup.xml", '<spatial name="string"')
    assert (cup.what, cup.line) == ("tendon `string`'s length limit [0, 0.3]", string)
    fish = {n.capability: n for n in load_mjcf(SUITE / "fish.xml").needs}[TENDON]
    assert (fish.what, fish.line) == ("tendon `fins_sym`'s stiffness", _line(SUITE / "fish.xml", 'name="fins_sym"'))
    quadruped = {n.capability: n for n in load_mjcf(SUITE / "quadruped.xml").needs}[EQUALITY]
    assert quadruped.what.startswith("equality `coupling_front_left`: holds tendon `coupling_front_left` at a length: "
                                     "a coupling of 3 joints (`pitch_front_left`, `knee_front_left`, "
                                     "`ankle_front_left`)") and quadruped.what.endswith("(and 3 more)")  # fmt: skip
    assert quadruped.line == _line(SUITE / "quadruped.xml", '<tendon name="coupling_front_left"')


def _equality_residual(d: Any, e: int) -> float:
    """MuJoCo's own violation of equality ``e`` (its constraint row's ``efc_pos``), after mj_forward."""
    rows = [i for i in range(d.nefc) if d.efc_type[i] == mujoco.mjtConstraint.mjCNSTR_EQUALITY and d.efc_id[i] == e]
    (row,) = rows
    return float(d.efc_pos[row])


def _holds(file_or_text: Path | str, follower: str, mimic: MimicDesc) -> None:
    """Wherever the leader is, MuJoCo's equality is satisfied with the follower at multiplier x leader + offset
    (positions from qpos0, the description's zero) to rounding, and violated in proportion off it."""
    m = (mujoco.MjModel.from_xml_path(str(file_or_text)) if isinstance(file_or_text, Path)
         else mujoco.MjModel.from_xml_string(file_or_text))  # fmt: skip
    d = mujoco.MjData(m)
    lead, follow = (int(m.jnt_qposadr[m.joint(n).id]) for n in (mimic.leader, follower))
    for x in (-0.7, -0.1, 0.0, 0.3, 1.1):
        d.qpos[:] = m.qpos0
        d.qpos[lead] = m.qpos0[lead] + x
        d.qpos[follow] = m.qpos0[follow] + mimic.multiplier * x + mimic.offset
        mujoco.mj_forward(m, d)
        held = _equality_residual(d, 0)
        assert abs(held) <= 1e-12, (x, held)  # sums of a few terms below 2 in size: rounding, 64 eps
        d.qpos[follow] += 0.01
        mujoco.mj_forward(m, d)
        assert abs(_equality_residual(d, 0)) >= 1e-3  # off its place, the equality is violated


def test_manipulators_coupling_is_the_mimic_mujoco_holds() -> None:
    (finger,) = [j for j in load_mjcf(SUITE / "manipulator.xml").joints if j.mimic is not None]
    assert finger.name == "finger" and finger.mimic is not None
    _holds(SUITE / "manipulator.xml", "finger", finger.mimic)


KINDS = """<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <body name="a" pos="0 0 1"><joint name="ja" type="hinge" axis="0 1 0" ref="0.3"/>
      <geom type="capsule" fromto="0 0 0 .3 0 0" size=".02"/></body>
    <body name="b" pos="0 .5 1"><joint name="jb" type="slide" axis="1 0 0" ref="-0.2"/>
      <geom type="capsule" fromto="0 0 0 .3 0 0" size=".02"/></body>
  </worldbody>
  <tendon>
    <fixed name="both"><joint joint="ja" coef="-0.5"/><joint joint="jb" coef="2"/></fixed>
    <fixed name="tb"><joint joint="jb" coef="2"/></fixed>
    <fixed name="ta"><joint joint="ja" coef="-0.5"/></fixed>
  </tendon>
  <equality>%s</equality>
</mujoco>
"""
#: each kind of equality that is a mimic (module docstring of runner.language.mjcf_needs), with the joints'
#: zero away from qpos = 0 (`ref`) and an offset, and the mimic derived by hand from MuJoCo's definitions
EQUALITIES = {
    # -0.5 xa + 2 xb = 0.1: xb = 0.25 xa + 0.05 (the tendon's second joint follows its first)
    "one tendon": ('<tendon tendon1="both" polycoef="0.1 7 0 0 0"/>', MimicDesc("ja", 0.25, 0.05)),
    # 2 xb = 0.1 + 3 (-0.5 xa): xb = -0.75 xa + 0.05
    "two tendons": ('<tendon tendon1="tb" tendon2="ta" polycoef="0.1 3 0 0 0"/>', MimicDesc("ja", -0.75, 0.05)),
    # xb = 0.1 + 3 xa
    "joints": ('<joint joint1="jb" joint2="ja" polycoef="0.1 3 0 0 0"/>', MimicDesc("ja", 3.0, 0.1)),
}


@pytest.mark.parametrize("kind", list(EQUALITIES))
def test_each_kind_of_coupling_is_the_mimic_mujoco_holds(tmp_path: Path, kind: str) -> None:
    element, expected = EQUALITIES[kind]
    (tmp_path / "kinds.xml").write_text(KINDS % element)
    desc = load_mjcf(tmp_path / "kinds.xml")
    line = (KINDS % element).splitlines().index(f"  <equality>{element}</equality>") + 1
    assert [(n.capability, n.line) for n in desc.needs] == [("joint:mimic", line)]  # named where DART, ODE refuse
    (jb,) = [j for j in desc.joints if j.mimic is not None]
    assert jb.name == "jb" and jb.mimic is not None
    assert (jb.mimic.leader, jb.mimic.multiplier, jb.mimic.offset) == pytest.approx(
        (expected.leader, expected.multiplier, expected.offset), abs=1e-15)  # fmt: skip
    _holds(KINDS % element, "jb", jb.mimic)


REFUSED = {
    "a joint held in place": ('<joint joint1="jb" polycoef="0.1 0 0 0 0"/>', "holds joint `jb` in place"),
    "a quadratic": ('<joint joint1="jb" joint2="ja" polycoef="0 1 0.5 0 0"/>', "by a polynomial of degree above 1"),
    "a weld": ('<weld body1="a" body2="b"/>', "a weld constraint"),
    "a connect": ('<connect body1="a" body2="b" anchor="0 0 0"/>', "a connect constraint"),
    "one joint's tendon": ('<tendon tendon1="tb"/>', "holds tendon `tb` at a length: a joint held in place"),
    "a loop": ('<joint joint1="jb" joint2="ja"/><joint joint1="ja" joint2="jb"/>', "closes a loop"),
}


@pytest.mark.parametrize("kind", list(REFUSED))
def test_other_equalities_stay_refused_naming_why(tmp_path: Path, kind: str) -> None:
    element, why = REFUSED[kind]
    (tmp_path / "kinds.xml").write_text(KINDS % element)
    needs = {n.capability: n for n in load_mjcf(tmp_path / "kinds.xml").needs}
    assert set(needs) == ({EQUALITY, "joint:mimic"} if kind == "a loop" else {EQUALITY})  # the loop's first holds
    need = needs[EQUALITY]
    assert why in need.what
    assert need.line == (KINDS % element).splitlines().index(f"  <equality>{element}</equality>") + 1


def test_an_inactive_equality_is_inert(tmp_path: Path) -> None:
    (tmp_path / "kinds.xml").write_text(KINDS % '<weld name="w" body1="a" body2="b" active="false"/>')
    desc = load_mjcf(tmp_path / "kinds.xml")
    assert desc.needs == () and any("inactive at the start" in n and "`w`" in n for n in desc.notes)


# --- a coupled pair on the engines against mujoco.mj_step on the same file ----------------------------------
# The pair of tests/backends/test_mimic.py (its module docstring derives the bounds used here), written in MJCF
# with a tendon equality: lead + 2 follow = 0.4, i.e. follow = -0.5 lead + 0.2. MuJoCo's equality is soft:
# with solref (tau, zeta) = (0.02, 1) and solimp d = 0.99 flat, the row r = lead + 2 follow - 0.4 obeys
# r'' = (1 - d) a0 - d B r' - d^2 K r with d^2 K = 1 / (tau zeta)^2 and d B = 2 / tau (critically damped), so
# from r = 0 |r| <= (1 - d) max|a0| tau^2 (the impulse response t exp(-t/tau) integrates to tau^2), doubled
# for the discrete step (w h = 0.1); a0 = a_lead + 2 a_follow of two free pendulums. The follower is r / 2 off.
G, H, T = 9.81, 0.002, 1.0
MULTIPLIER, OFFSET = -0.5, 0.2
MA, RA, IA = 1.0, 0.25, 0.02 + 1.0 * 0.25**2  # leader: mass, COM from the hinge, inertia about the hinge
MB, RB, IB = 0.5, 0.2, 0.01 + 0.5 * 0.2**2
J = IA + MULTIPLIER**2 * IB
TAU, D = 0.02, 0.99
ROUNDING = 1e-9  # the trace's rounding of positions
PAIR = """<mujoco model="mimic_pair">
  <compiler angle="radian"/>
  <option timestep="0.002" gravity="0 0 -9.81"/>
  <worldbody>
    <body name="arm_a">
      <joint name="lead" type="hinge" axis="0 1 0"/>
      <inertial pos=".25 0 0" mass="1" diaginertia=".001 .02 .02"/>
      <geom type="box" pos=".25 0 0" size=".25 .02 .02" contype="0" conaffinity="0"/>
    </body>
    <body name="arm_b" pos="0 .3 0">
      <joint name="follow" type="hinge" axis="0 1 0"/>
      <inertial pos=".2 0 0" mass=".5" diaginertia=".001 .01 .01"/>
      <geom type="box" pos=".2 0 0" size=".2 .02 .02" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <tendon><fixed name="coupling"><joint joint="lead" coef="1"/><joint joint="follow" coef="2"/></fixed></tendon>
  <equality>
    <tendon name="coupling" tendon1="coupling" polycoef="0.4 0 0 0 0" solref="0.02 1" solimp="0.99 0.99 0.001 0.5 2"/>
  </equality>
</mujoco>
"""
SCENARIO = f"""schema_version: 1
scenario: mjcf-mimic-pair
world: {{gravity: [0, 0, {-G}], dt: {H}, duration: {T}}}
bodies:
  ground: {{plane: {{}}, motion: static, pos: [0, 0, -1]}}
robots:
  r: {{mjcf: pair.xml, pos: [0, 0, 1]}}
"""


def _free_acceleration() -> float:
    """max|a0| of the tendon row lead + 2 follow, each arm a free pendulum."""
    return G * (MA * RA / IA + 2.0 * MB * RB / IB)


def _soft_bound() -> float:
    """The follower off its place under MuJoCo's soft equality (above): 2 (1 - d) max|a0| tau^2 / 2."""
    return 2.0 * (1.0 - D) * _free_acceleration() * TAU**2 / 2.0


def _reference() -> np.ndarray:
    """The leader of the rigid pair: semi-implicit Euler on the one-coordinate pendulum (test_mimic)."""
    q, v, out = 0.0, 0.0, [0.0]
    for _ in range(round(T / H)):
        v += H * (MA * G * RA * math.cos(q) + MULTIPLIER * MB * G * RB * math.cos(MULTIPLIER * q + OFFSET)) / J
        q += H * v
        out.append(q)
    return np.array(out)


def _drift(track: float) -> float:
    """The leader off the rigid pair's when the follower is up to ``track`` off its place: the gravity torque
    it changes (test_mimic) and the follower's own inertia, |m| I_b e'' / J, whose double integral is e."""
    return abs(MULTIPLIER) * MB * G * RB * track / J * T * T / 2 + abs(MULTIPLIER) * IB * track / J


def test_the_pair_under_mujocos_own_step() -> None:
    """The reference itself: `mj_step` on the file, from the start the runner gives it (the follower where its
    leader puts it), follows the mimic within the soft equality's bound."""
    lead, follow = _mj_step_pair()
    gap = float(np.max(np.abs(follow - (MULTIPLIER * lead + OFFSET))))
    assert gap <= _soft_bound(), (gap, _soft_bound())
    off = float(np.max(np.abs(lead - _reference())))
    assert off <= _drift(_soft_bound()), (off, _drift(_soft_bound()))
    assert float(np.ptp(lead)) > 2.0  # it swung through most of a half turn


def _mj_step_pair() -> tuple[np.ndarray, np.ndarray]:
    """(lead, follow) at every step of `mj_step` on the file, from the start the runner gives it (the follower
    where its leader puts it)."""
    m = mujoco.MjModel.from_xml_string(PAIR)
    d = mujoco.MjData(m)
    d.qpos[1] = OFFSET
    lead, follow = [0.0], [OFFSET]
    for _ in range(round(T / H)):
        mujoco.mj_step(m, d)
        lead.append(float(d.qpos[0]))
        follow.append(float(d.qpos[1]))
    return np.array(lead), np.array(follow)


@pytest.mark.slow
def test_on_mujoco_the_pair_is_the_files_own_equality(tmp_path: Path) -> None:
    """With the model's options the runner on MuJoCo is `mj_step` on the file (the same engine, model and
    start: equal to the trace's rounding, tests/backends/test_mjcf_native.py): the mimic read from the
    equality adds no second constraint there."""
    (tmp_path / "pair.xml").write_text(PAIR)
    (tmp_path / "pair.yaml").write_text(SCENARIO.replace(f"duration: {T}}}", f"duration: {T}, options: model}}"))
    result = run_loaded(load_scenario(tmp_path / "pair.yaml"), "mujoco", tmp_path / "mujoco")
    assert result.status == "passed" and result.trace is not None, result.failure
    trace = read_trace(result.trace)
    lead, follow = _mj_step_pair()
    assert np.max(np.abs(trace.joints["r.lead"].position - lead)) <= ROUNDING
    assert np.max(np.abs(trace.joints["r.follow"].position - follow)) <= ROUNDING


def _tracking_bound(engine: str) -> float:
    """test_mimic's bounds: PyBullet's gear and DART's coupler with its solved offset exact (rounding), Drake's
    SAP coupler, MuJoCo the file's own soft equality (above), ODE's force pair held to float32 (test_mimic's)."""
    if engine == "ode":
        return mimic_tests._tracking_bound(engine, 0.0, mimic_tests._fastest(), 4.0)
    bound = ROUNDING + round(T / H) * get_backend(engine).precision.eps * 4.0
    if engine == "drake":
        eps = 0.1**2 / (4 * math.pi**2)
        bound += 2.0 * eps / (1.0 - eps) * G * (MB * RB / IB + abs(MULTIPLIER) * MA * RA / IA) * H**2
    if engine == "mujoco":
        bound += _soft_bound()
    return bound


def _declares_mimic(engine: str) -> bool:
    return Capability.JOINT_MIMIC in get_backend(engine).capabilities


@pytest.mark.slow
@pytest.mark.parametrize("engine", [e for e in INSTALLED if _declares_mimic(e)])
def test_the_pair_runs_as_a_mimic(tmp_path: Path, engine: str) -> None:
    (tmp_path / "pair.xml").write_text(PAIR)
    (tmp_path / "pair.yaml").write_text(SCENARIO)
    result = run_loaded(load_scenario(tmp_path / "pair.yaml"), engine, tmp_path / engine)
    assert result.status == "passed", result.failure
    assert result.trace is not None
    trace = read_trace(result.trace)
    lead, follow = trace.joints["r.lead"].position, trace.joints["r.follow"].position
    assert lead[0] == 0.0 and follow[0] == pytest.approx(OFFSET, abs=ROUNDING)  # started where its leader puts it
    track = _tracking_bound(engine)
    gap = float(np.max(np.abs(follow - (MULTIPLIER * lead + OFFSET))))
    assert gap <= track, (engine, gap, track)
    off = float(np.max(np.abs(lead - _reference()[: len(lead)])))
    # ODE steps each arm in maximal coordinates: its own distance from the joint-space reference (test_mimic)
    assert off <= _drift(track - ROUNDING) + 2 * ROUNDING + mimic_tests._maximal_coordinates_gap(tmp_path, engine)
    assert float(np.ptp(lead)) > 2.0


@pytest.mark.parametrize("engine", [*(e for e in INSTALLED if not _declares_mimic(e)), "fake"])  # fake: none
def test_an_engine_without_mimic_refuses_the_pair_up_front(tmp_path: Path, engine: str) -> None:
    (tmp_path / "pair.xml").write_text(PAIR)
    (tmp_path / "pair.yaml").write_text(SCENARIO)
    command = [sys.executable, "-m", "runner", "validate", str(tmp_path / "pair.yaml"), "-b", engine]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 2 and "joint:mimic" in done.stderr and f"`{engine}`" in done.stderr, done.stderr
    line = PAIR.splitlines().index("  <equality>") + 2
    assert f"pair.xml:{line}: equality `coupling`: joint `follow` follows `lead`" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_an_acting_tendon_is_refused_through_the_cli_naming_it(tmp_path: Path) -> None:
    """ball_in_cup, unmodified (its `<include>`s beside it): the string's limit, at its line, exit 2."""
    shutil.copy(SUITE / "ball_in_cup.xml", tmp_path)
    shutil.copytree(SUITE / "common", tmp_path / "common")
    (tmp_path / "cup.yaml").write_text(SCENARIO.replace("pair.xml", "ball_in_cup.xml"))
    line = _line(SUITE / "ball_in_cup.xml", '<spatial name="string"')
    for command in ("validate", "run"):
        args = [sys.executable, "-m", "runner", command, str(tmp_path / "cup.yaml"), "-b", "pybullet"]
        done = subprocess.run(args + (["--no-trace"] if command == "run" else []), cwd=ROOT, capture_output=True,
                              text=True, timeout=300, check=False)  # fmt: skip
        assert done.returncode == 2, (command, done.stderr)
        assert f"ball_in_cup.xml:{line}: tendon `string`'s length limit [0, 0.3]" in done.stderr, done.stderr
