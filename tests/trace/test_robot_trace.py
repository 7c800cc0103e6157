"""A robot's trace: the scene draws each link's visual meshes (the URDF's <visual>, in its materials' colours)
and, on /scene/collision, its collision shapes (convex hulls as triangle lists) at their local poses, and each
joint's axis; /bodies and /joints nest a robot's links and joints (`/bodies.arm.link.vel.z`), and the
report's scene reads them back. The trace is PyBullet's run of the arm scenario (a real engine; the checks
are of the scene and the names, which every engine writes alike)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backends.types import ShapeKind
from reports.scene3d.model import SceneModel, scene_model
from reports.scene3d.scene_channel import read_scene_updates
from reports.trace_reader import read_trace
from runner.compile.program import build_program
from runner.language.load import load_scenario
from runner.sim.run import run_loaded
from tests.paths import ROOT

pytestmark = pytest.mark.slow
ARM = ROOT / "scenarios" / "robots" / "kuka_arm.yaml"


@pytest.fixture(scope="module")
def trace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    result = run_loaded(load_scenario(ARM), "pybullet", tmp_path_factory.mktemp("robot"))
    assert result.passed and result.trace is not None
    return Path(result.trace)


def _entities(trace: Path) -> dict[str, dict]:
    return {e["id"]: e for _, update in read_scene_updates(trace) for e in update["entities"]}


def test_collision_scene_holds_every_hull_triangle_at_its_pose(trace: Path) -> None:
    world = build_program(load_scenario(ARM)).world
    entities = _entities(trace)
    for body in world.bodies:
        if body.shape.kind is not ShapeKind.COMPOUND:
            continue
        entity = entities[f"collision/{body.name}"]
        assert entity["frame_id"] == body.name
        triangles = entity["triangles"]
        assert len(triangles) == len(body.shapes)
        for prim, placed in zip(triangles, body.shapes, strict=True):
            assert placed.shape.mesh is not None
            assert len(prim["points"]) == 3 * len(placed.shape.mesh.faces)
            first = placed.shape.mesh.vertices[placed.shape.mesh.faces[0][0]]
            assert [prim["points"][0].get(k, 0.0) for k in "xyz"] == pytest.approx(first, abs=1e-12)


#: kuka_iiwa/model.urdf: each link's one <visual> mesh (meshes/link_<k>.obj) and its material
#: (Grey 0.2 0.2 0.2, Blue 0.5 0.7 1.0, Orange 1.0 0.4235 0.0392); link 7 is painted red by the scenario
KUKA_MATERIALS = ["grey", "blue", "blue", "orange", "blue", "blue", "orange", None]
RGB = {"grey": (0.2, 0.2, 0.2), "blue": (0.5, 0.7, 1.0), "orange": (1.0, 0.423529411765, 0.0392156862745),
       None: (0.9, 0.2, 0.2)}  # fmt: skip


def test_scene_draws_each_link_by_its_visual_mesh_in_its_material(trace: Path) -> None:
    import trimesh

    from runner.language.robot_desc import resolve_file

    entities = _entities(trace)
    folder = resolve_file("@pybullet_data/kuka_iiwa/meshes", ROOT)
    for k, material in enumerate(KUKA_MATERIALS):
        entity = entities[f"body/arm.lbr_iiwa_link_{k}"]
        (prim,) = entity["triangles"]  # one model per link: its one <visual>
        mesh = trimesh.load(str(folder / f"link_{k}.obj"), force="mesh", process=True)
        assert len(prim["indices"]) == 3 * len(mesh.faces)  # under the 5,000-triangle bound: kept whole
        assert len(prim["points"]) == len(mesh.vertices)
        points = np.array([[p.get(c, 0.0) for c in "xyz"] for p in prim["points"]])
        assert np.allclose(points.min(axis=0), mesh.bounds[0], atol=1e-12)
        assert np.allclose(points.max(axis=0), mesh.bounds[1], atol=1e-12)
        colour = prim["color"]
        assert [colour.get(c, 0.0) for c in "rgb"] == pytest.approx(RGB[material], abs=1e-12)
        assert not entity.get("arrows")


def test_scene_draws_each_joint_axis_through_its_anchor(trace: Path) -> None:
    """Every KUKA joint turns about its link's local z (the URDF's axis 0 0 1) at the link frame's origin."""
    entities = _entities(trace)
    for k in range(1, 8):
        entity = entities[f"joint/arm.lbr_iiwa_joint_{k}"]
        assert entity["frame_id"] == f"arm.lbr_iiwa_link_{k}"
        (arrow,) = entity["arrows"]
        (ball,) = entity["spheres"]
        length = arrow["shaft_length"] + arrow["head_length"]
        o = arrow["pose"]["orientation"]  # +x turned onto the axis: (w, x, y, z) = (cos 45, 0, -sin 45, 0)
        assert [o.get(c, 0.0) for c in "wxyz"] == pytest.approx([0.5**0.5, 0.0, -(0.5**0.5), 0.0], abs=1e-12)
        start = [arrow["pose"]["position"].get(c, 0.0) for c in "xyz"]
        assert start == pytest.approx([0.0, 0.0, -length / 2], abs=1e-12)  # centred on the anchor
        assert [ball["pose"]["position"].get(c, 0.0) for c in "xyz"] == pytest.approx([0, 0, 0], abs=1e-12)


def test_links_and_joints_read_back_by_name(trace: Path) -> None:
    data = read_trace(trace)
    link = data.bodies["arm.lbr_iiwa_link_7"]
    assert np.allclose(link.pos[0], (0.0, 0.0, 1.261), atol=1e-9) and np.all(np.isfinite(link.vel))
    assert "arm.lbr_iiwa_joint_2" in data.joints
    times, z = data.series("arm.lbr_iiwa_link_7.pos.z")
    assert len(times) == len(z) == 501 and z[0] == pytest.approx(1.261, abs=1e-9)
    assert len(data.series("arm.lbr_iiwa_joint_2.position")[1]) == 501


def test_report_scene_from_messages_and_from_metadata_agree(trace: Path) -> None:
    """A cut-off trace draws from body_specs: the collision shapes, the same primitives as /scene/collision's."""
    data = read_trace(trace)
    drawn = scene_model(data).entities_at(0.0)
    import json

    from reports import trace_format as tf

    fallback = SceneModel.from_specs(json.loads(data.scenario[tf.KEY_BODY_SPECS])).entities_at(0.0)
    a, b = drawn["collision/arm.lbr_iiwa_link_3"].primitives, fallback["body/arm.lbr_iiwa_link_3"].primitives
    assert drawn["collision/arm.lbr_iiwa_link_3"].layer == "collision"
    assert [p.kind for p in a] == [p.kind for p in b] == ["triangles"]
    assert np.allclose(np.asarray(a[0].points), np.asarray(b[0].points), atol=1e-12)
