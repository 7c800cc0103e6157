"""URDF as the established loaders read it (docs/robots.md, "Quirks accepted"): what pybullet's loader reads
past is read here too, with the same numbers; what no loader can read is refused at its line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.language.robot_desc import ModelDesc
from tests.language.test_robot_models import DATA, GOOD_URDF, _issue, _line_of, _scenario

CUBE = np.array([[float(c) for c in line.split()[1:4]] for line in (DATA / "cube.obj").read_text().splitlines()
                 if line.startswith("v ")])  # fmt: skip


def test_a_declaration_after_a_comment_and_a_trailing_nul_are_read_past(tmp_path: Path) -> None:
    """biped2d_pybullet.urdf declares XML after a comment; humanoid.urdf ends with a NUL byte."""
    text = "<!-- a comment first -->\n" + GOOD_URDF + "\x00"
    loaded = load_scenario(_scenario(tmp_path, text))
    assert {link.name for link in loaded.robots["bot"].links} == {"base", "arm"}


@pytest.mark.parametrize(("scale", "factors"), [("1 1 1 1", (1, 1, 1)), ("2", (2, 2, 2)), ("1 2 3", (1, 2, 3))])
def test_every_mesh_scale_form(tmp_path: Path, scale: str, factors: tuple[float, float, float]) -> None:
    """One number scales every axis; three are x, y, z; of four (racecar's), pybullet reads the first three."""
    text = GOOD_URDF.replace('<mesh filename="MESH"/>', f'<mesh filename="MESH" scale="{scale}"/>')
    mesh = load_scenario(_scenario(tmp_path, text)).robots["bot"].link("arm").shapes[0].shape.mesh
    assert mesh is not None
    extent = np.ptp(np.asarray(mesh.vertices), axis=0)  # the hull keeps the cube's corners
    assert np.allclose(extent, np.ptp(CUBE, axis=0) * np.asarray(factors), rtol=1e-12)


def test_two_numbers_are_no_scale(tmp_path: Path) -> None:
    text = GOOD_URDF.replace('<mesh filename="MESH"/>', '<mesh filename="MESH" scale="1 2"/>')
    _, line, message = _issue(_scenario(tmp_path, text))
    assert "mesh scale" in message and line == _line_of(text, "scale=")


def test_package_uri_is_found_beside_the_model(tmp_path: Path) -> None:
    """franka_panda/panda.urdf names `package://meshes/...` for its own `meshes/` folder."""
    loaded = load_scenario(_scenario(tmp_path, GOOD_URDF, mesh="package://meshes/cube.obj"))
    assert loaded.robots["bot"].link("arm").shapes[0].shape.mesh is not None


def test_package_uri_on_ros_package_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    elsewhere = tmp_path / "ws" / "src" / "my_robot" / "meshes"
    elsewhere.mkdir(parents=True)
    elsewhere.joinpath("c.obj").write_text((DATA / "cube.obj").read_text())
    model = tmp_path / "models"
    model.mkdir()
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws" / "src"))
    loaded = load_scenario(_scenario(model, GOOD_URDF, mesh="package://my_robot/meshes/c.obj"))
    assert loaded.robots["bot"].link("arm").shapes[0].shape.mesh is not None


def test_a_missing_package_names_package_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(_scenario(tmp_path, GOOD_URDF, mesh="package://nowhere_pkg/m.obj"))
    message = caught.value.issues[0].message
    assert "package `nowhere_pkg`" in message and "package_root" in message and "ROS_PACKAGE_PATH" in message


RULES_URDF = """\
<robot name="rules">
  <link name="base">
    <inertial><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <link name="flange"><collision><origin xyz="0 0 0.05"/><geometry><sphere radius="0.02"/></geometry></collision></link>
  <joint name="weld" type="fixed"><parent link="base"/><child link="flange"/>
    <origin xyz="0.3 0 0" rpy="0 0 1.5707963267948966"/></joint>
  <link name="arm"><collision><geometry><box size="0.1 0.2 0.4"/></geometry></collision></link>
  <joint name="elbow" type="revolute"><parent link="flange"/><child link="arm"/><origin xyz="0 0.1 0"/>
    <axis xyz="0 0 1"/><limit lower="0.5" upper="1.0" effort="1" velocity="1"/></joint>
  <link name="slide">
    <inertial><mass value="1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="rail" type="prismatic"><parent link="arm"/><child link="slide"/><axis xyz="1 0 0"/>
    <limit lower="1" upper="-1" effort="1" velocity="1"/></joint>
</robot>
"""


def _rules(tmp_path: Path) -> ModelDesc:
    path = _scenario(tmp_path, RULES_URDF, extra=", fixed: true")
    return load_scenario(path).robots["bot"]


def test_a_massless_link_on_a_fixed_joint_merges_into_its_parent(tmp_path: Path) -> None:
    """flange (no <inertial>) is welded 0.3 m along x, turned 90 deg about z: its sphere, 5 cm up in its own
    frame, sits on base at (0.3, 0, 0.05); the elbow hangs from base now."""
    desc = _rules(tmp_path)
    assert [link.name for link in desc.links] == ["base", "arm", "slide"]
    (placed,) = desc.link("base").shapes
    assert np.allclose(placed.pos, (0.3, 0.0, 0.05), atol=1e-12) and placed.shape.radius == 0.02
    elbow = next(j for j in desc.joints if j.name == "elbow")
    assert elbow.parent == "base" and "weld" not in {j.name for j in desc.joints}


def test_a_moving_link_without_inertial_gets_pybullets_default(tmp_path: Path) -> None:
    """1 kg, the inertia of its box (0.1 x 0.2 x 0.4 m): m/12 (b^2 + c^2), ... about its centre."""
    arm = _rules(tmp_path).link("arm")
    expected = np.diag([0.2**2 + 0.4**2, 0.1**2 + 0.4**2, 0.1**2 + 0.2**2]) / 12.0
    assert arm.mass == 1.0 and np.allclose(np.asarray(arm.inertia), expected, rtol=1e-12)


def test_a_zero_tensor_gets_a_usable_one(tmp_path: Path) -> None:
    """slide has mass and a zero tensor and no shape: a 1 cm solid sphere's, 2/5 m r^2."""
    slide = _rules(tmp_path).link("slide")
    assert np.allclose(np.asarray(slide.inertia), np.eye(3) * 0.4 * 1.0 * 0.01**2, rtol=1e-12)


def test_a_start_outside_the_limits_is_clamped_and_lower_above_upper_is_no_limit(tmp_path: Path) -> None:
    """elbow's 0 is below [0.5, 1.0]: it starts at 0.5 rad (arm's frame turned 0.5 rad about z), its limits
    count from there, [0, 0.5]; rail's lower > upper is pybullet's "no limit"."""
    desc = _rules(tmp_path)
    elbow = next(j for j in desc.joints if j.name == "elbow")
    rail = next(j for j in desc.joints if j.name == "rail")
    assert (elbow.lo, elbow.hi) == pytest.approx((0.0, 0.5), abs=1e-15) and rail.lo is None and rail.hi is None
    # arm's frame: base -> weld (turn 90 deg) -> elbow origin, then the 0.5 rad start: 90 deg + 0.5 rad about z
    w, x, y, z = desc.link("arm").quat
    assert (x, y) == pytest.approx((0.0, 0.0), abs=1e-12) and 2 * np.arctan2(z, w) == pytest.approx(np.pi / 2 + 0.5)
    assert any("elbow" in note and "starts at 0.5" in note for note in desc.notes)


def test_numbers_as_pybullet_reads_them(tmp_path: Path) -> None:
    """Commas separate numbers (bike.urdf) and an item is its leading number (biped2d_pybullet's `-1.57.`)."""
    text = GOOD_URDF.replace('<origin xyz="0 0 0.1" rpy="0 0 0.5"/>', '<origin xyz="0, 0, 0.1" rpy="0 0 0.5."/>')
    assert text != GOOD_URDF
    desc = load_scenario(_scenario(tmp_path, text)).robots["bot"]
    w, x, y, z = desc.link("arm").quat
    assert 2 * np.arctan2(z, w) == pytest.approx(0.5, abs=1e-12) and desc.link("arm").pos[2] == pytest.approx(0.1)


def test_an_inertia_no_body_has_is_balanced_as_mujoco_does(tmp_path: Path) -> None:
    """Principal moments 0.01, 0.01, 0.05 (A + B < C): each becomes their mean, 0.07 / 3 (balanceinertia)."""
    text = GOOD_URDF.replace('ixx="0.05" ixy="0.01" ixz="0" iyy="0.04" iyz="0" izz="0.03"',
                             'ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.05"')  # fmt: skip
    assert text != GOOD_URDF
    tensor = np.asarray(load_scenario(_scenario(tmp_path, text)).robots["bot"].link("arm").inertia)
    assert np.allclose(np.linalg.eigvalsh(tensor), 0.07 / 3, rtol=1e-12)
