"""What a model draws (runner.language.visuals): a URDF's <visual>s and an MJCF's visible geoms, read into
``LinkDesc.visuals``, and the bound on their meshes.

The meshes: a mesh over the bound is simplified by vertex clustering into at most the bound's triangles,
every vertex the mean of original vertices (so a convex mesh's vertices stay inside it), no triangle
collapsed, the same bytes every time; one under the bound is kept as it is; a model over its budget
is cut down in proportion. The readers: KUKA iiwa's URDF (one OBJ mesh per link, Grey/Blue/Orange
materials) and MuJoCo's hello_mjcf.xml (a 2 x 2 m red floor, a green box)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import trimesh

from backends.types import ShapeKind
from runner.language.robot_desc import resolve_file
from runner.language.visuals import MAX_TRIANGLES, simplified
from tests.paths import ROOT


def test_a_mesh_over_the_bound_is_clustered_under_it_the_same_way_every_time() -> None:
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=1.0)  # 20,480 triangles
    vertices, faces = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    v, f = simplified(vertices, faces)
    assert 0 < len(f) <= MAX_TRIANGLES
    assert f.min() >= 0 and f.max() < len(v)
    assert np.all((f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2]))
    assert np.linalg.norm(v, axis=1).max() <= 1.0 + 1e-12  # means of points of a convex surface: inside it
    again = simplified(vertices.copy(), faces.copy())
    assert v.tobytes() == again[0].tobytes() and f.tobytes() == again[1].tobytes()
    small_v, small_f = simplified(vertices, faces[:100])
    assert small_v is not None and np.array_equal(small_f, faces[:100])  # under the bound: kept whole


def test_a_model_over_its_budget_is_cut_down_in_proportion() -> None:
    from runner.language.urdf import load_urdf
    from runner.language.visuals import within_budget

    desc = load_urdf(resolve_file("@pybullet_data/kuka_iiwa/model.urdf", ROOT), None, True, False)
    links = list(desc.links)
    counts = [len(link.visuals[0].shape.mesh.faces) for link in links]  # type: ignore[union-attr]
    budget = sum(counts) // 4
    cut = within_budget(links, budget)
    after = [len(link.visuals[0].shape.mesh.faces) for link in cut]
    assert sum(after) <= budget
    assert all(a <= c * budget // sum(counts) for a, c in zip(after, counts, strict=True))


def test_urdf_visuals_are_the_files_meshes_in_their_materials() -> None:
    from runner.language.urdf import load_urdf

    desc = load_urdf(resolve_file("@pybullet_data/kuka_iiwa/model.urdf", ROOT), None, True, False)
    folder = resolve_file("@pybullet_data/kuka_iiwa/meshes", ROOT)
    materials = {"Grey": (0.2, 0.2, 0.2, 1.0), "Blue": (0.5, 0.7, 1.0, 1.0),
                 "Orange": (1.0, 0.423529411765, 0.0392156862745, 1.0)}  # fmt: skip
    names = ["Grey", "Blue", "Blue", "Orange", "Blue", "Blue", "Orange", "Grey"]
    for k, link in enumerate(desc.links):
        (visual,) = link.visuals
        assert visual.shape.kind is ShapeKind.TRIMESH and visual.shape.mesh is not None
        assert visual.color == pytest.approx(materials[names[k]], abs=1e-12)
        mesh: Any = trimesh.load(str(folder / f"link_{k}.obj"), force="mesh", process=True)
        assert len(visual.shape.mesh.faces) == len(mesh.faces)
        assert np.array_equal(np.asarray(visual.shape.mesh.vertices), np.asarray(mesh.vertices))


def test_mjcf_visuals_are_its_visible_geoms_with_a_plane_at_its_size() -> None:
    pytest.importorskip("mujoco", reason="engine not installed: mujoco")
    from runner.language.mjcf import load_mjcf

    desc = load_mjcf(resolve_file("@pybullet_data/mjcf/hello_mjcf.xml", ROOT))
    (floor,) = desc.link("worldbody").visuals
    assert floor.shape.kind is ShapeKind.PLANE and floor.shape.size[:2] == (2.0, 2.0)  # size="1 1 0.1": half
    assert floor.color == pytest.approx((0.9, 0.0, 0.0, 1.0), abs=1e-7)  # rgba as float32
    (box,) = desc.links[1].visuals
    assert box.shape.kind is ShapeKind.BOX and box.shape.size == pytest.approx((0.2, 0.4, 0.6), abs=1e-12)
