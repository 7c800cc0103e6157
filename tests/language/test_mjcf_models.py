"""MJCF read as MuJoCo reads it (issue 28, item 2): what MuJoCo accepts loads; what only MuJoCo runs is
listed as the capabilities the model needs, so another engine refuses it before the run (exit 2, the
feature and the engine named); a file MuJoCo refuses is refused at MuJoCo's line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from backends.types import MODEL_FILE_CAPABILITIES, ShapeKind
from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.language.robot_desc import MimicDesc
from tests.paths import ROOT

pytest.importorskip("mujoco", reason="reading MJCF needs MuJoCo's compiler (the `mujoco` extra)")
DATA = Path(__import__("pybullet_data").getDataPath()) / "mjcf"


def _scenario(folder: Path, model: str, text: str | None = None, world: str = "") -> Path:
    xml = folder / f"{model}.xml"
    xml.write_text(text if text is not None else (DATA / f"{model}.xml").read_text())
    path = folder / f"{model}.yaml"
    path.write_text(
        f"schema_version: 1\nscenario: t\nworld: {{dt: 0.01, duration: 0.2{world}}}\nbodies:\n"
        "  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [50, 50, 0]}\n"
        f"robots:\n  r: {{mjcf: {model}.xml}}\n"
    )
    return path


def _run(path: Path, backend: str) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "runner", "run", str(path), "-b", backend, "--no-trace", "-q"]
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)


def test_actuators_and_damping_load_and_are_listed(tmp_path: Path) -> None:
    loaded = load_scenario(_scenario(tmp_path, "inverted_pendulum"))  # `<custom>`-free, `<default>`s, RK4
    desc = loaded.robots["r"]
    assert desc.needs == ()  # damping="1" from the default class: every engine runs it (the runner's motor)
    assert {j.name: j.dynamics.damping for j in desc.joints if j.kind != "fixed"} == {"slider": 1.0, "hinge": 1.0}
    assert [(a.name, a.kind, a.joint) for a in desc.actuators] == [("slide", "motor", "slider")]
    assert desc.timestep == 0.02 and desc.gravity == (0.0, 0.0, -9.81)
    world = build_program(loaded).world
    assert world.models[0].needs == frozenset()
    assert {j.name: j.dynamics.damping for j in world.joints} == {"r.slider": 1.0, "r.hinge": 1.0}
    assert world.required_capabilities() & MODEL_FILE_CAPABILITIES == world.models[0].needs


CONSTRAINED = """<mujoco>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="ja" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 .3 0 0" size=".02"/>
      <body name="b" pos=".3 0 0">
        <joint name="jb" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 .3 0 0" size=".02"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="t" limited="true" range="-.5 .5"><joint joint="ja" coef="1"/><joint joint="jb" coef="1"/></fixed>
  </tendon>
  <equality><joint joint1="jb" joint2="ja" polycoef="0 .5 0 0 0"/></equality>
  <sensor><jointpos joint="ja"/></sensor>
  <custom><numeric name="n" data="1"/></custom>
</mujoco>
"""


def test_an_acting_tendon_runs_on_mujoco_and_is_refused_up_front_elsewhere(tmp_path: Path) -> None:
    """The tendon's length limit acts (constraint:tendon, named at its line); the joint equality jb = 0.5 ja is
    a mimic (runner.language.mjcf_needs), which PyBullet would run: the refusal names the tendon alone."""
    path = _scenario(tmp_path, "constrained", CONSTRAINED)
    desc = load_scenario(path).robots["r"]
    limit = "tendon `t`'s length limit [-0.5, 0.5]"
    follows = "equality `equality_0`: joint `jb` follows `ja`"
    assert [(n.capability, n.what) for n in desc.needs] == [("joint:mimic", follows), ("constraint:tendon", limit)]
    tendon_line = next(k for k, line in enumerate(CONSTRAINED.splitlines(), 1) if '<fixed name="t"' in line)
    assert desc.needs[1].line == tendon_line
    assert {j.name: j.mimic for j in desc.joints if j.mimic is not None} == {"jb": MimicDesc("ja", 0.5, 0.0)}
    ran = _run(path, "mujoco")
    assert ran.returncode == 0, ran.stderr
    refused = _run(path, "pybullet")
    assert refused.returncode == 2
    assert "needs constraint:tendon (robot `r`: constrained.xml:" in refused.stderr, refused.stderr
    assert f"constrained.xml:{tendon_line}: tendon `t`'s length limit [-0.5, 0.5])" in refused.stderr
    assert "`pybullet`" in refused.stderr and "Traceback" not in refused.stderr


SEVERAL = """<mujoco>
  <compiler angle="degree"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 .1"/>
    <body name="torso" pos="0 0 1">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <joint name="pitch" type="hinge" axis="0 1 0" range="-30 30"/>
      <geom type="ellipsoid" size=".2 .1 .05"/>
      <geom type="sphere" size=".05" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_several_joints_per_body_ellipsoids_and_visual_geoms(tmp_path: Path) -> None:
    desc = load_scenario(_scenario(tmp_path, "several", SEVERAL)).robots["r"]
    kinds = {j.name: (j.kind, j.parent, j.child) for j in desc.joints}
    assert kinds == {n: (k, "worldbody", "torso") for n, k in (("x", "slider"), ("z", "slider"), ("pitch", "hinge"))}
    pitch = next(j for j in desc.joints if j.name == "pitch")
    assert pitch.lo == pytest.approx(-0.5235987755982988, abs=1e-15)  # 30 degrees, converted by MuJoCo
    (shape,) = desc.link("torso").shapes  # the visual sphere (contype = conaffinity = 0) is not a collision shape
    assert shape.shape.kind is ShapeKind.CONVEX and shape.shape.mesh is not None
    radii = [max(abs(v[k]) for v in shape.shape.mesh.vertices) for k in range(3)]
    assert radii == pytest.approx([0.2, 0.1, 0.05], abs=1e-12)  # the hull's vertices lie on the ellipsoid
    assert desc.needs == ()  # several joints in one body run on every engine (a chain elsewhere than MuJoCo)
    for engine in ("mujoco", "ode"):
        assert _run(tmp_path / "several.yaml", engine).returncode == 0, engine


def test_a_file_mujoco_refuses_is_refused_at_mujocos_line(tmp_path: Path) -> None:
    """Also through the legacy upgrade (runner.language.mjcf_legacy): humanoid_fixed's `fixed` joint on line 25
    is removed before MuJoCo reads the file, and a bad geom type on line 40 is still MuJoCo's line 40."""
    lines = (DATA / "humanoid_fixed.xml").read_text().split("\n")
    assert 'type="capsule"' in lines[39]
    lines[39] = lines[39].replace('type="capsule"', 'type="capsul"')
    path = _scenario(tmp_path, "humanoid_fixed", "\n".join(lines))
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(path)
    issue = caught.value.issues[0]
    assert issue.file == str(tmp_path / "humanoid_fixed.xml") and issue.line == 40 and "capsul" in issue.message


def test_options_model_needs_the_models_step_and_gravity(tmp_path: Path) -> None:
    path = _scenario(tmp_path, "inverted_pendulum", world=", options: model")  # the model's timestep: 0.02
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(path)
    assert "dt / substeps (0.01 s) must be the model's timestep 0.02 s" in caught.value.issues[0].message
    path.write_text(path.read_text().replace("dt: 0.01", "dt: 0.02"))
    assert load_scenario(path).model.world.options == "model"


def test_a_placed_robot_starts_where_the_description_puts_it_on_mujoco(tmp_path: Path) -> None:
    """MuJoCo builds the robot from its file in a frame at `pos`/`hpr`: its bodies start at the poses the
    compiled world gives them (the description's forward kinematics moved by the placement), to rounding."""
    import numpy as np

    from backends.registry import create_backend

    path = _scenario(tmp_path, "several", SEVERAL)
    path.write_text(
        path.read_text().replace("mjcf: several.xml}", "mjcf: several.xml, pos: [1, 2, 0.5], hpr: [30, 20, 10]}")
    )
    world = build_program(load_scenario(path)).world
    with create_backend("mujoco", world) as sim:
        states = sim.body_states()
        for i, body in enumerate(world.bodies):
            assert np.allclose(states.pos[i], body.pos, rtol=0, atol=1e-12), body.name
            assert np.allclose(states.quat[i], body.quat, rtol=0, atol=1e-12), body.name


@pytest.mark.parametrize("model", ["hopper", "humanoid_fixed", "swimmer"])
def test_a_legacy_file_is_built_on_mujoco_from_its_upgrade(tmp_path: Path, model: str) -> None:
    """MuJoCo's backend reads the upgraded text (``ModelFile.xml``, runner.language.mjcf_legacy), not the file
    MuJoCo 4 refuses: the bodies start where the description (the same upgrade) puts them, to rounding."""
    import numpy as np

    from backends.registry import create_backend

    path = _scenario(tmp_path, model)
    path.write_text(path.read_text().replace(f"mjcf: {model}.xml}}", f"mjcf: {model}.xml, pos: [1, 2, 0.5]}}"))
    world = build_program(load_scenario(path)).world
    assert world.models[0].xml and 'type="fixed"' not in world.models[0].xml  # upgraded (humanoid_fixed: the weld)
    with create_backend("mujoco", world) as sim:
        states = sim.body_states()
        for i, body in enumerate(world.bodies):
            assert np.allclose(states.pos[i], body.pos, rtol=0, atol=1e-12), body.name
            assert np.allclose(states.quat[i], body.quat, rtol=0, atol=1e-12), body.name


OUT_OF_RANGE = """<mujoco>
  <compiler angle="degree"/>
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" range="30 60"/>
      <geom type="capsule" fromto="0 0 0 .4 0 0" size=".02" mass="1"/>
      <body name="hand" pos=".4 0 0">
        <joint name="wrist" type="hinge" axis="0 1 0" ref="-90" range="-110 110"/>
        <geom type="sphere" size=".03" mass=".2"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_a_zero_outside_the_range_starts_at_the_nearest_end(tmp_path: Path, engine: str) -> None:
    """pybullet_data's ant: ankles with range="30 100" at a zero of 0. The joint starts at 30 degrees (noted),
    read from the file's zero; a `ref` (MuJoCo's qpos0) shifts the range into the joint's own coordinate."""
    import math

    from reports.trace_reader import read_trace
    from runner.sim.run import run_loaded

    loaded = load_scenario(_scenario(tmp_path, "ranged", OUT_OF_RANGE))
    desc = loaded.robots["r"]
    lo = math.radians(30)
    assert desc.start == (("shoulder", pytest.approx(lo, abs=1e-12)),)
    assert "`shoulder`" in desc.notes[0] and "nearest end" in desc.notes[0]
    wrist = next(j for j in desc.joints if j.name == "wrist")
    assert (wrist.lo, wrist.hi) == pytest.approx((math.radians(-20), math.radians(200)), abs=1e-12)  # -110 + 90
    result = run_loaded(loaded, engine, tmp_path / engine)
    assert result.status == "passed" and result.trace is not None, result.failure
    trace = read_trace(result.trace)
    assert float(trace.joints["r.shoulder"].position[0]) == pytest.approx(lo, abs=1e-9)
    hand = trace.bodies["r.hand"].pos[0]  # the hinge about +y turns +x towards -z: the hand 0.4 sin(30) lower
    assert hand[0] == pytest.approx(0.4 * math.cos(lo), abs=1e-9)
    assert hand[2] == pytest.approx(1 - 0.4 * math.sin(lo), abs=1e-9)


WELDED = """<mujoco>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="ja" type="hinge" axis="0 1 0"/>
      <geom type="sphere" size=".16"/>
      <body name="b" pos=".1 0 0">
        <geom type="sphere" size=".16"/>
        <body name="c" pos=".1 0 0">
          <joint name="jc" type="hinge" axis="0 1 0"/>
          <geom type="sphere" size=".16"/>
          <body name="d" pos=".1 0 0">
            <joint name="jd" type="hinge" axis="0 1 0"/>
            <geom type="sphere" size=".16"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_mujocos_parent_filter_works_on_weld_roots(tmp_path: Path) -> None:
    """b has no joint: MuJoCo welds it into a, so a and b never touch (same weld root) and neither do a and c
    (c's parent weld root is a); c and d are parent and child; a and d, b and d may touch. The spheres (r 0.16,
    0.1 apart) all overlap; MuJoCo's own contacts are exactly the pairs not excluded."""
    import mujoco

    desc = load_scenario(_scenario(tmp_path, "welded", WELDED)).robots["r"]
    pairs = {frozenset(p) for p in desc.excluded}
    assert {frozenset(("a", "b")), frozenset(("a", "c")), frozenset(("b", "c"))} <= pairs
    assert frozenset(("a", "d")) not in pairs
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "welded.xml"))  # MuJoCo's own: every overlapping pair
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    names = [model.body(int(model.geom_bodyid[g])).name for g in range(model.ngeom)]
    touching = {frozenset((names[c.geom1], names[c.geom2])) for c in data.contact[: data.ncon]}
    every = {frozenset((x, y)) for x in "abcd" for y in "abcd" if x < y}
    assert touching == every - pairs == {frozenset(("a", "d")), frozenset(("b", "d"))}
