"""A robot in Rerun looks like its model: the KUKA arm's .rrd (`scenario export TRACE --to rerun`), read back with
rerun-sdk's own reader, draws each link by its URDF visual mesh (one ``Mesh3D`` per link, every triangle of
meshes/link_<k>.obj, in the material's colour), keeps the collision hulls apart at ``<link>/collision`` (hidden
by the blueprint), and draws each joint's axis (``Arrows3D``) at ``<link>/joint/<joint>``.

rerun-sdk is the optional `viewers` extra: skipped without it (SCENARIO_REQUIRE_RERUN=1 makes that a failure).
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from runner.language.load import load_scenario
from runner.language.robot_desc import resolve_file
from runner.sim.run import run_loaded
from tests.paths import ROOT

REQUIRED = os.environ.get("SCENARIO_REQUIRE_RERUN") == "1"
INSTALLED = importlib.util.find_spec("rerun") is not None
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not INSTALLED and not REQUIRED, reason="rerun-sdk is not installed (pip install '.[viewers]')"),
]
ARM = ROOT / "scenarios" / "robots" / "kuka_arm.yaml"
#: kuka_iiwa/model.urdf's materials per link (Grey, Blue, Orange); link 7 is painted red by the scenario
RGB = [(0.2, 0.2, 0.2), (0.5, 0.7, 1.0), (0.5, 0.7, 1.0), (1.0, 0.4235, 0.0392), (0.5, 0.7, 1.0), (0.5, 0.7, 1.0),
       (1.0, 0.4235, 0.0392), (0.9, 0.2, 0.2)]  # fmt: skip


@pytest.fixture(scope="module")
def columns(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, list[Any]]]:
    if not INSTALLED:
        pytest.fail("SCENARIO_REQUIRE_RERUN=1 but rerun-sdk is not installed (pip install '.[viewers]')")
    from rerun.chunk import RrdReader

    from reports.rerun_export import export_rerun

    out = tmp_path_factory.mktemp("rrd")
    result = run_loaded(load_scenario(ARM), "pybullet", out)
    assert result.trace is not None
    rrd, _ = export_rerun(Path(result.trace), out / "arm.rrd")
    found: dict[str, dict[str, list[Any]]] = {}
    for chunk in RrdReader(rrd).stream().to_chunks():
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            if ":" in name:
                found.setdefault(chunk.entity_path, {}).setdefault(name, []).extend(batch.column(name).to_pylist())
    return found


def test_each_link_is_its_visual_mesh_in_its_material(columns: dict[str, dict[str, list[Any]]]) -> None:
    import trimesh

    folder = resolve_file("@pybullet_data/kuka_iiwa/meshes", ROOT)
    for k, rgb in enumerate(RGB):
        link = columns[f"/world/arm.lbr_iiwa_link_{k}"]
        (vertices,) = link["Mesh3D:vertex_positions"]  # one mesh, logged once
        mesh = trimesh.load(str(folder / f"link_{k}.obj"), force="mesh", process=True)
        assert len(vertices) == 3 * len(mesh.faces)  # every triangle of the file (under the 5,000 bound)
        points = np.asarray(vertices, dtype=float)
        tol = 1e-6 * float(np.abs(mesh.bounds).max())  # float32 positions
        assert np.allclose(points.min(axis=0), mesh.bounds[0], atol=tol)
        assert np.allclose(points.max(axis=0), mesh.bounds[1], atol=tol)
        (colours,) = link["Mesh3D:vertex_colors"]
        rgba = {int(c) for c in colours}
        assert len(rgba) == 1  # packed 0xRRGGBBAA
        packed = rgba.pop()
        got = [(packed >> shift & 0xFF) / 255 for shift in (24, 16, 8)]
        assert got == pytest.approx(rgb, abs=0.5 / 255 + 1e-4)  # 8 bits per channel
        hull = columns[f"/world/arm.lbr_iiwa_link_{k}/collision"]
        assert "Mesh3D:vertex_positions" in hull


def test_each_joint_axis_is_an_arrow(columns: dict[str, dict[str, list[Any]]]) -> None:
    for k in range(1, 8):
        joint = columns[f"/world/arm.lbr_iiwa_link_{k}/joint/arm.lbr_iiwa_joint_{k}"]
        ((vector,),) = joint["Arrows3D:vectors"]
        assert vector[0] == pytest.approx(0.0, abs=1e-6) and vector[1] == pytest.approx(0.0, abs=1e-6)
        assert vector[2] > 0  # along the link's z, the URDF's axis 0 0 1
