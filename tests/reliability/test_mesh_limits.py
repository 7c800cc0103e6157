"""Mesh files a model names are bounded before they are read (issue 31; docs/reliability.md, "Limits"): a
200 MB STL took 2.7 GB and over 90 s. Over MAX_MESH_BYTES (from the file's stat), or declaring more than
MAX_MESH_TRIANGLES triangles or MAX_MESH_VERTICES vertices (from a binary STL's header, or counting an
OBJ's lines), the mesh is refused at the model file's line naming it: exit 2 from `validate` and `run`,
within a second. The oversized files are sparse (truncated to size, nothing written): if the file were read,
the test would take far longer than its bound.
"""

from __future__ import annotations

import struct
import time
from pathlib import Path

import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.language.mesh_limits import MAX_MESH_BYTES, MAX_MESH_TRIANGLES, MAX_MESH_VERTICES
from tests.ci.conftest import cli

FAST = 1.0  # seconds: the checks read a stat and at most a header; generous for a loaded 2-core machine

SCENARIO = """\
schema_version: 1
scenario: big-mesh
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 0.05}}
bodies:
  ground: {{plane: {{}}, motion: static}}
robots:
  r: {{{kind}: {file}, pos: [0, 0, 1]}}
"""
URDF = """\
<robot name="r">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision>
      <geometry><mesh filename="{mesh}"/></geometry>
    </collision>
  </link>
</robot>
"""
MJCF = """\
<mujoco>
  <asset>
    <mesh name="big" file="{mesh}"/>
  </asset>
  <worldbody>
    <body name="b" pos="0 0 1"><freejoint/><geom type="mesh" mesh="big"/></body>
  </worldbody>
</mujoco>
"""


def _sparse_stl(path: Path, triangles: int, size: int) -> None:
    """A binary STL header declaring ``triangles``, the file made ``size`` bytes long without writing them."""
    with path.open("wb") as handle:
        handle.write(b"\0" * 80 + struct.pack("<I", triangles))
        handle.truncate(size)


def _refused(capsys: pytest.CaptureFixture[str], tmp_path: Path, kind: str, mesh: str) -> str:
    model = tmp_path / ("robot.urdf" if kind == "urdf" else "model.xml")
    model.write_text((URDF if kind == "urdf" else MJCF).format(mesh=mesh))
    scenario = tmp_path / "s.yaml"
    scenario.write_text(SCENARIO.format(kind=kind, file=model.name))
    with pytest.raises(ScenarioValidationError):  # the first load also imports the model readers (seconds)
        load_scenario(scenario, None)
    start = time.perf_counter()
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(scenario, None)
    took = time.perf_counter() - start
    assert took < FAST, took
    code, validated = cli(capsys, "validate", scenario)
    run_code, ran = cli(capsys, "run", scenario, "--out", tmp_path / "out")
    assert (code, run_code) == (2, 2), validated + ran
    assert "Traceback" not in validated + ran
    issues = [str(issue) for issue in info.value.issues]
    assert len(issues) == 1, issues
    line = next(n for n, text in enumerate(model.read_text().splitlines(), 1) if mesh in text)
    column = model.read_text().splitlines()[line - 1].index(mesh) + 1
    assert issues[0].startswith(f"{model}:{line}:{column}: robots.r.{kind}: "), issues
    return issues[0]


def test_a_mesh_file_over_the_size_limit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _sparse_stl(tmp_path / "big.stl", 1, MAX_MESH_BYTES + 1)
    issue = _refused(capsys, tmp_path, "urdf", "big.stl")
    assert f"the mesh big.stl is larger than {MAX_MESH_BYTES} bytes ({MAX_MESH_BYTES + 1})" in issue


def test_a_binary_stl_declaring_too_many_triangles(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    n = MAX_MESH_TRIANGLES + 1
    _sparse_stl(tmp_path / "many.stl", n, 84 + 50 * n)  # a well-formed size, under the byte limit
    assert 84 + 50 * n <= MAX_MESH_BYTES
    issue = _refused(capsys, tmp_path, "urdf", "many.stl")
    assert f"the mesh many.stl holds {n} triangles; at most {MAX_MESH_TRIANGLES} are read" in issue


def test_an_obj_with_too_many_vertices(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    n = MAX_MESH_VERTICES + 1
    (tmp_path / "many.obj").write_bytes(b"v 0 0 0\n" * n + b"f 1 2 3\n")  # 2 MB
    issue = _refused(capsys, tmp_path, "urdf", "many.obj")
    assert f"the mesh many.obj holds {n} vertices; at most {MAX_MESH_VERTICES} are read" in issue


def test_an_mjcf_mesh_over_the_size_limit_is_refused_before_mujoco_reads_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("mujoco")
    _sparse_stl(tmp_path / "big.stl", 1, MAX_MESH_BYTES + 1)
    issue = _refused(capsys, tmp_path, "mjcf", "big.stl")
    assert f"the mesh big.stl is larger than {MAX_MESH_BYTES} bytes" in issue


def test_a_mesh_in_an_included_mjcf_file_is_bounded_too(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("mujoco")
    _sparse_stl(tmp_path / "big.stl", 1, MAX_MESH_BYTES + 1)
    assets = '<mujoco>\n  <asset>\n    <mesh name="big" file="big.stl"/>\n  </asset>\n</mujoco>\n'
    (tmp_path / "assets.xml").write_text(assets)
    model = tmp_path / "model.xml"
    model.write_text('<mujoco>\n  <include file="assets.xml"/>\n  <worldbody>\n    <body name="b" pos="0 0 1">'
                     '<freejoint/><geom type="mesh" mesh="big"/></body>\n  </worldbody>\n</mujoco>\n')  # fmt: skip
    scenario = tmp_path / "s.yaml"
    scenario.write_text(SCENARIO.format(kind="mjcf", file="model.xml"))
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(scenario, None)
    (issue,) = [str(i) for i in info.value.issues]
    assert issue.startswith(f"{tmp_path / 'assets.xml'}:3:") and "the mesh big.stl is larger than" in issue, issue
    code, out = cli(capsys, "validate", scenario)
    assert code == 2 and "Traceback" not in out, out
