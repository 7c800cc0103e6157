"""URDF as the established loaders read it (docs/robots.md, "Quirks accepted"): what pybullet's loader reads
past is read here too, with the same numbers; what no loader can read is refused at its line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
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
