"""A robot's trace: the scene draws each link's shapes (convex hulls as triangle lists) at their local poses,
/bodies and /joints nest a robot's links and joints (`/bodies.arm.link.vel.z`), and the report's scene reads
them back. The trace is PyBullet's run of the arm scenario (a real engine; the checks are of the scene and
the names, which every engine writes alike)."""

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


def test_scene_holds_every_hull_triangle_at_its_pose(trace: Path) -> None:
    world = build_program(load_scenario(ARM)).world
    (_, update), *_ = read_scene_updates(trace)
    entities = {e["id"]: e for e in update["entities"]}
    for body in world.bodies:
        if body.shape.kind is not ShapeKind.COMPOUND:
            continue
        entity = entities[f"body/{body.name}"]
        assert entity["frame_id"] == body.name
        triangles = entity["triangles"]
        assert len(triangles) == len(body.shapes)
        for prim, placed in zip(triangles, body.shapes, strict=True):
            assert placed.shape.mesh is not None
            assert len(prim["points"]) == 3 * len(placed.shape.mesh.faces)
            first = placed.shape.mesh.vertices[placed.shape.mesh.faces[0][0]]
            assert [prim["points"][0].get(k, 0.0) for k in "xyz"] == pytest.approx(first, abs=1e-12)


def test_links_and_joints_read_back_by_name(trace: Path) -> None:
    data = read_trace(trace)
    link = data.bodies["arm.lbr_iiwa_link_7"]
    assert np.allclose(link.pos[0], (0.0, 0.0, 1.261), atol=1e-9) and np.all(np.isfinite(link.vel))
    assert "arm.lbr_iiwa_joint_2" in data.joints
    times, z = data.series("arm.lbr_iiwa_link_7.pos.z")
    assert len(times) == len(z) == 501 and z[0] == pytest.approx(1.261, abs=1e-9)
    assert len(data.series("arm.lbr_iiwa_joint_2.position")[1]) == 501


def test_report_scene_from_messages_and_from_metadata_agree(trace: Path) -> None:
    """A cut-off trace draws from body_specs: the same primitives as the scene channel's."""
    data = read_trace(trace)
    drawn = scene_model(data).entities_at(0.0)
    import json

    from reports import trace_format as tf

    fallback = SceneModel.from_specs(json.loads(data.scenario[tf.KEY_BODY_SPECS])).entities_at(0.0)
    name = "body/arm.lbr_iiwa_link_3"
    a, b = drawn[name].primitives, fallback[name].primitives
    assert [p.kind for p in a] == [p.kind for p in b] == ["triangles"]
    assert np.allclose(np.asarray(a[0].points), np.asarray(b[0].points), atol=1e-12)
