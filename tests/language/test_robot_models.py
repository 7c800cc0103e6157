"""Robot models (URDF, MJCF): bad models are refused at the model file's line with exit 2; the compiled
world's numbers agree with what yourdfpy and trimesh (tools we did not write) read from the same files."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from backends.types import Capability, Motion, ShapeKind
from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.language.robot_desc import data_root
from tests.paths import ROOT

DATA = data_root("@pybullet_data")[0]  # type: ignore[index]
KUKA = DATA / "kuka_iiwa" / "model.urdf"

GOOD_URDF = """\
<?xml version="1.0"?>
<robot name="two">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <link name="arm">
    <inertial><origin xyz="0 0 0.25" rpy="0 0.3 0"/><mass value="2"/>
      <inertia ixx="0.05" ixy="0.01" ixz="0" iyy="0.04" iyz="0" izz="0.03"/></inertial>
    <collision><origin xyz="0 0 0.25"/><geometry><mesh filename="MESH"/></geometry></collision>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0.1" rpy="0 0 0.5"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
</robot>
"""


def _scenario(folder: Path, urdf_text: str, mesh: str = "meshes/cube.obj", extra: str = "") -> Path:
    (folder / "meshes").mkdir(exist_ok=True)
    cube = (DATA / "cube.obj").read_text()
    (folder / "meshes" / "cube.obj").write_text(cube)
    (folder / "robot.urdf").write_text(urdf_text.replace("MESH", mesh))
    path = folder / "s.yaml"
    path.write_text(
        textwrap.dedent(f"""\
        schema_version: 1
        scenario: t
        world: {{dt: 0.01, duration: 1}}
        bodies:
          ground: {{plane: {{}}, motion: static}}
        robots:
          bot: {{urdf: robot.urdf, pos: [1, 2, 3], hpr: [30, 0, 0]{extra}}}
        """)
    )
    return path


def _issue(path: Path) -> tuple[str, int, str]:
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(path)
    issue = caught.value.issues[0]
    return issue.file, issue.line, issue.message


def _column(path: Path) -> int:
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(path)
    return caught.value.issues[0].column


def _line_of(text: str, needle: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


def _column_of(text: str, needle: str) -> int:
    """1-based, as the issues count columns."""
    return next(line.index(needle) + 1 for line in text.splitlines() if needle in line)


def test_missing_mesh_is_refused_at_its_line(tmp_path: Path) -> None:
    path = _scenario(tmp_path, GOOD_URDF, mesh="meshes/nothing.obj")
    file, line, message = _issue(path)
    assert file == str(tmp_path / "robot.urdf") and line == _line_of(GOOD_URDF, "MESH")
    assert _column(path) == _column_of(GOOD_URDF, "MESH")  # at the file name
    assert "meshes/nothing.obj` does not exist" in message


def test_joint_naming_a_missing_link_is_refused_at_its_line(tmp_path: Path) -> None:
    text = GOOD_URDF.replace('<child link="arm"/>', '<child link="hand"/>')
    file, line, message = _issue(_scenario(tmp_path, text))
    assert file.endswith("robot.urdf") and line == _line_of(text, 'child link="hand"')
    assert _column(tmp_path / "s.yaml") == _column_of(text, '<child link="hand"')  # at the <child> element
    assert "names child link `hand`, which the model does not define" in message


FINGER_URDF = GOOD_URDF.replace(
    "</robot>",
    """  <link name="finger">
    <inertial><mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
  </link>
  <joint name="grip" type="prismatic">
    <parent link="arm"/><child link="finger"/><origin xyz="0 0 0.5"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
    <mimic joint="shoulder" multiplier="0.1" offset="0.02"/>
  </joint>
</robot>""",
)


@pytest.mark.parametrize(
    ("mimic", "kind", "found"),
    [
        ('<mimic joint="elbow"/>', "revolute", "names a joint the model does not define"),
        ('<mimic joint="shoulder"/>', "revolute", "names itself"),
        ("", "fixed", "must be revolute, continuous or prismatic"),
    ],
)
def test_a_bad_mimic_is_refused_at_its_line(tmp_path: Path, mimic: str, kind: str, found: str) -> None:
    text = GOOD_URDF.replace("<limit ", f"{mimic}\n    <limit ") if mimic else FINGER_URDF
    text = text.replace('name="grip" type="prismatic"', f'name="grip" type="{kind}"')
    file, line, message = _issue(_scenario(tmp_path, text))
    assert file.endswith("robot.urdf") and line == _line_of(text, "<mimic")
    assert _column(tmp_path / "s.yaml") == _column_of(text, "<mimic")
    assert "<mimic joint=" in message and found in message


def test_a_mimic_starts_where_its_leader_puts_it(tmp_path: Path) -> None:
    """`initial` on the leader moves its follower: multiplier x the leader's start + offset, and the follower
    reads in the file's coordinate from the start; the compiled coupling is then already satisfied."""
    path = _scenario(tmp_path, FINGER_URDF, extra=", initial: {joints: {shoulder: 0.5}}")
    program = build_program(load_scenario(path))
    (coupling,) = program.world.couplings
    assert (coupling.joint, coupling.leader, coupling.multiplier) == ("bot.grip", "bot.shoulder", 0.1)
    assert coupling.offset == pytest.approx(0.0, abs=1e-15)  # started in place
    assert program.joint_zeros["bot.grip"] == pytest.approx(0.1 * 0.5 + 0.02, abs=1e-15)
    assert Capability.JOINT_MIMIC in program.world.required_capabilities()


def test_malformed_xml_is_refused_at_its_line(tmp_path: Path) -> None:
    text = GOOD_URDF.replace("</joint>", "</joint", 1)
    file, line, message = _issue(_scenario(tmp_path, text))
    broken = _line_of(text, "</joint")  # the parser notices the unclosed tag where the next one starts
    assert file.endswith("robot.urdf") and broken <= line <= broken + 1 and message.startswith("malformed XML")
    assert _column(tmp_path / "s.yaml") >= 1  # the parser's column


def test_package_path_escaping_its_root_is_refused(tmp_path: Path) -> None:
    (tmp_path / "pkgs").mkdir()
    path = _scenario(tmp_path, GOOD_URDF, mesh="package://../../etc/passwd", extra=", package_root: pkgs")
    file, line, message = _issue(path)
    assert file.endswith("robot.urdf") and line == _line_of(GOOD_URDF, "MESH")
    assert _column(path) == _column_of(GOOD_URDF, "MESH")
    assert "outside its root" in message and str((tmp_path / "pkgs").resolve()) in message


def test_package_path_resolves_under_the_root(tmp_path: Path) -> None:
    (tmp_path / "pkgs" / "mine").mkdir(parents=True)
    (tmp_path / "pkgs" / "mine" / "c.obj").write_text((DATA / "cube.obj").read_text())
    loaded = load_scenario(_scenario(tmp_path, GOOD_URDF, mesh="package://mine/c.obj", extra=", package_root: pkgs"))
    arm = loaded.robots["bot"].link("arm")
    assert arm.shapes[0].shape.mesh is not None and arm.shapes[0].shape.mesh.source == "c.obj"


BAD_MODELS = {  # the issue's four bad models: (the URDF's text, what the error says, where it points)
    "missing-mesh": (GOOD_URDF.replace("MESH", "meshes/nothing.obj"), "does not exist", "meshes/nothing.obj"),
    "missing-link": (GOOD_URDF.replace('<parent link="base"/>', '<parent link="nowhere"/>'), "does not define",
                     '<parent link="nowhere"'),
    "malformed-xml": (GOOD_URDF.replace("</joint>", "</joint", 1), "malformed XML", None),
    "package-escape": (GOOD_URDF.replace("MESH", "package://../../etc/passwd"), "outside its root",
                       "package://../../etc/passwd"),
}  # fmt: skip


@pytest.mark.parametrize("kind", sorted(BAD_MODELS))
def test_a_bad_model_exits_2_at_its_file_line_and_column(tmp_path: Path, kind: str) -> None:
    """`validate` and `run` both refuse it with exit 2, no traceback, and ``robot.urdf:LINE:COLUMN``."""
    text, says, near = BAD_MODELS[kind]
    (tmp_path / "pkgs").mkdir()
    path = _scenario(tmp_path, text, extra=", package_root: pkgs")
    (tmp_path / "robot.urdf").write_text(text)  # as written (no MESH left to replace)
    if near is None:
        line, column = _issue(path)[1], _column(path)
    else:
        line, column = _line_of(text, near), _column_of(text, near)
    for command in (["validate", str(path)], ["run", str(path), "--no-trace"]):
        done = subprocess.run(
            [sys.executable, "-m", "runner", *command], capture_output=True, text=True, cwd=tmp_path, timeout=120
        )
        out = done.stderr + done.stdout
        assert done.returncode == 2, out
        assert "Traceback" not in out and says in out
        assert f"robot.urdf:{line}:{column}: " in out and column >= 1, out


def test_override_naming_a_missing_joint_is_refused_in_the_scenario(tmp_path: Path) -> None:
    path = _scenario(tmp_path, GOOD_URDF, extra=", joints: {shouldr: {motor: {fmax: 1}}}")
    file, line, message = _issue(path)
    assert file == str(path) and line == 7 and "unknown joint `shouldr`; did you mean `shoulder`?" in message


def test_compiled_world_matches_the_urdf(tmp_path: Path) -> None:
    """Masses, COM offsets, the inertia tensor through its diagonalisation, hull vertices, start poses."""
    import trimesh
    import yourdfpy

    from backends.geometry import quat_rotate

    path = _scenario(tmp_path, GOOD_URDF)
    world = build_program(load_scenario(path)).world
    base, arm = world.bodies[1], world.bodies[2]
    assert (base.name, arm.name) == ("bot.base", "bot.arm") and base.motion is arm.motion is Motion.DYNAMIC
    urdf = yourdfpy.URDF.load(str(tmp_path / "robot.urdf"), load_meshes=False)
    link = urdf.link_map["arm"]
    assert arm.mass == link.inertial.mass == 2.0
    assert np.allclose(arm.com, link.inertial.origin[:3, 3], atol=1e-15)
    r = link.inertial.origin[:3, :3]
    assert np.allclose(arm.inertia_tensor(), r @ link.inertial.inertia @ r.T, atol=1e-12)
    assert arm.shape.kind is ShapeKind.COMPOUND and arm.shapes[0].shape.kind is ShapeKind.CONVEX
    hull = trimesh.load(str(tmp_path / "meshes" / "cube.obj"), force="mesh").convex_hull
    assert len(arm.shapes[0].shape.mesh.vertices) == len(hull.vertices) == 8  # type: ignore[union-attr]
    # the start pose: the robot's placement (pos, heading 30 deg about z) times yourdfpy's forward kinematics
    fk = urdf.get_transform("arm", "base")
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    place = np.array([[c, -s, 0, 1], [s, c, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1.0]])
    expected = place @ fk
    assert np.allclose(arm.pos, expected[:3, 3], atol=1e-12)
    assert np.allclose([quat_rotate(arm.quat, e) for e in np.eye(3)], expected[:3, :3].T, atol=1e-12)
    joint = world.joints[0]
    assert joint.name == "bot.shoulder" and joint.body == "bot.arm" and joint.other == "bot.base"
    assert np.allclose(joint.axis, expected[:3, :3] @ [0, 1, 0], atol=1e-12) and (joint.lo, joint.hi) == (-1.0, 1.0)
    assert world.excluded_pairs == (("bot.arm", "bot.base"),)
    assert {
        Capability.SHAPE_COMPOUND,
        Capability.SHAPE_CONVEX,
        Capability.COM_OFFSET,
        Capability.COLLISION_FILTER,
    } <= world.required_capabilities()


def test_kuka_links_match_yourdfpy() -> None:
    import trimesh
    import yourdfpy

    world = build_program(load_scenario(ROOT / "scenarios" / "robots" / "kuka_arm.yaml")).world
    urdf = yourdfpy.URDF.load(str(KUKA), load_meshes=False)
    links = {b.name.split(".", 1)[1]: b for b in world.bodies if b.name.startswith("arm.")}
    assert len(links) == 8 and links["lbr_iiwa_link_0"].motion is Motion.STATIC
    for name, body in links.items():
        link = urdf.link_map[name]
        assert np.allclose(body.pos, urdf.get_transform(name, "lbr_iiwa_link_0")[:3, 3], atol=1e-12)
        mesh = link.collisions[0].geometry.mesh.filename
        hull = trimesh.load(str(KUKA.parent / mesh), force="mesh").convex_hull
        assert len(body.shapes[0].shape.mesh.vertices) == len(hull.vertices)  # type: ignore[union-attr]
        if body.motion is Motion.DYNAMIC:
            assert body.mass == link.inertial.mass and np.allclose(body.com, link.inertial.origin[:3, 3])
            assert np.allclose(np.diag(body.inertia_tensor()), np.diag(link.inertial.inertia))


def test_mjcf_model_through_mujoco() -> None:
    pytest.importorskip("mujoco", reason="mujoco not installed")
    world = build_program(load_scenario(ROOT / "scenarios" / "robots" / "mjcf_box.yaml")).world
    box = next(b for b in world.bodies if b.name == "hello.body_1")
    floor = next(b for b in world.bodies if b.name == "hello.worldbody")
    assert box.mass == pytest.approx(1000 * 0.2 * 0.4 * 0.6, rel=1e-12) and box.pos == (0.0, 0.0, 1.0)
    m = box.mass
    assert np.allclose(box.inertia, (m / 12 * (0.16 + 0.36), m / 12 * (0.04 + 0.36), m / 12 * (0.04 + 0.16)))
    assert box.shapes[0].shape.size == pytest.approx((0.2, 0.4, 0.6))
    assert floor.motion is Motion.STATIC and floor.shapes[0].shape.kind is ShapeKind.PLANE
    assert not world.joints and not world.excluded_pairs  # a free joint is no joint, and the box meets the floor


@pytest.mark.parametrize(
    ("extra", "top", "found"),
    [
        ("", "exclude_contacts: [[bot.arm, nothing]]\n", "unknown body `nothing`"),
        ("", "joints: {bot: {type: hinge, bodies: [ground, environment]}}\n", "has the name of a body or joint"),
        (", joints: {shoulder: {servo: {target: 0, gain: 200, fmax: 1}}}", "", "expected gain x dt <= 1"),
        (", joints: {shoulder: {servo: {target: state.nope, gain: 10, fmax: 1}}}", "", "unknown name `state.nope`"),
        (", links: {hand: {color: [1, 0, 0]}}", "", "unknown link `hand`"),
    ],
)
def test_scenario_side_mistakes_are_located_in_the_scenario(tmp_path: Path, extra: str, top: str, found: str) -> None:
    path = _scenario(tmp_path, GOOD_URDF, extra=extra)
    path.write_text(path.read_text() + top)
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(path)
    assert any(i.file == str(path) and i.line > 0 and found in i.message for i in caught.value.issues), str(
        caught.value
    )


def test_link_overrides_reach_the_compiled_world(tmp_path: Path) -> None:
    extra = ", fixed: true, links: {arm: {color: [1, 0, 0], surface: {mu: 0.25}}}, joints: {shoulder: {free: true}}"
    world = build_program(load_scenario(_scenario(tmp_path, GOOD_URDF, extra=extra))).world
    arm = next(b for b in world.bodies if b.name == "bot.arm")
    base = next(b for b in world.bodies if b.name == "bot.base")
    assert arm.color == (1.0, 0.0, 0.0, 1.0) and base.motion is Motion.STATIC and base.mass == 0.0
    assert world.surface("bot.arm", "ground").mu == 0.25 and world.surface("bot.base", "ground").mu == float("inf")
    shoulder = world.joints[0]
    assert shoulder.other is None and shoulder.lo is None and shoulder.hi is None  # to the environment, no stops


def test_static_meshes_as_triangles(tmp_path: Path) -> None:
    """`static_meshes: triangles`: the fixed root keeps its mesh's triangles (shape:trimesh); moving links hull."""
    import trimesh

    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 1}\nbodies:\n"
        "  floor: {plane: {}, motion: static}\n"
        'robots:\n  arm: {urdf: "@pybullet_data/kuka_iiwa/model.urdf", fixed: true, static_meshes: triangles}\n'
    )
    world = build_program(load_scenario(path)).world
    base = next(b for b in world.bodies if b.name == "arm.lbr_iiwa_link_0")
    mesh = trimesh.load(str(KUKA.parent / "meshes" / "link_0.stl"), force="mesh")
    assert base.shapes[0].shape.kind is ShapeKind.TRIMESH and base.motion is Motion.STATIC
    assert len(base.shapes[0].shape.mesh.faces) == len(mesh.faces)  # type: ignore[union-attr]
    assert np.allclose(np.asarray(base.shapes[0].shape.mesh.vertices), mesh.vertices)  # type: ignore[union-attr]
    assert all(b.shapes[0].shape.kind is ShapeKind.CONVEX for b in world.bodies[2:])
    assert Capability.SHAPE_TRIMESH in world.required_capabilities()


def test_mjcf_without_mujoco_names_the_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from runner.language import robots

    robots._read.cache_clear()
    monkeypatch.setitem(sys.modules, "mujoco", None)  # `import mujoco` raises ImportError
    (tmp_path / "m.xml").write_text((DATA / "mjcf" / "hello_mjcf.xml").read_text())
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 1}\nbodies:\n"
        "  floor: {plane: {}, motion: static}\nrobots:\n  p: {mjcf: m.xml}\n"
    )
    file, _, message = _issue(path)
    # no place in the model file to name: located at the scenario's `mjcf:` line
    assert file.endswith("s.yaml") and "pip install 'physics-scenarios[mujoco]'" in message
