"""The Foxglove layout (runner/trace/layout.py, runner/cli/layouts.py): what `scenario layout` writes, and
`scenario run` beside its traces. tests/trace/test_foxglove.py loads it in the real Foxglove Studio."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from reports import trace_format as tf
from runner.cli.layouts import layout_spec
from runner.language.load import load_files
from runner.trace.layout import LayoutSpec, layout
from tests.paths import ROOT

CLI = [sys.executable, "-m", "runner"]


def _cli(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def _panels(data: dict[str, Any]) -> set[str]:
    """The panel ids the mosaic places."""
    out: set[str] = set()

    def walk(node: Any) -> None:
        if isinstance(node, str):
            out.add(node)
        else:
            walk(node["first"])
            walk(node["second"])

    walk(data["layout"])
    return out


def test_the_layout_shows_the_scene_the_asserted_quantities_the_events_and_the_log() -> None:
    data = layout(layout_spec(load_files([ROOT / "scenarios" / "factory_physics.yaml"], None, True)))
    assert _panels(data) == set(data["configById"]) == {"3D!scene", "Plot!asserted", "Plot!asserted_m_per_s",
                                                         "Plot!asserted_N", "StateTransitions!events",
                                                         "RosOut!log"}  # fmt: skip
    scene = data["configById"]["3D!scene"]
    assert scene["followTf"] == tf.WORLD_FRAME and scene["topics"][tf.TOPIC_SCENE] == {"visible": True}
    assert scene["topics"][tf.TOPIC_SCENE_COLLISION] == {"visible": False}  # a model's collision shapes: on demand
    plots = {p["label"]: p["value"] for _, paths in _plots(data).items() for p in paths}
    # assertions read box.vel.z (kick), box.pos.z (apex), door.vel.x, box-door contact, slider.position
    assert plots["box.vel.z"] == "/bodies.box.vel.z"
    assert plots["box.pos.z"] == '/tf.transforms[:]{child_frame_id=="box"}.translation.z'
    assert plots["slider.position"] == "/joints.slider.position"
    assert plots["contact box-door force"] == '/contacts.pairs[:]{a=="box"}{b=="door"}.normal_force'
    events = [p["value"] for p in data["configById"]["StateTransitions!events"]["paths"]]
    assert events == ["/events.name", "/state.door_open"]
    assert data["configById"]["Plot!asserted"]["showPlotValuesInLegend"] is True
    # one unit per plot: the contact's newtons never scale the metres' axis
    units = {title: {p["label"] for p in paths} for title, paths in _plots(data).items()}
    assert units["Asserted quantities (N)"] == {"contact box-door force", "contact door-box force"}
    assert {"box.pos.z", "door.pos.x", "slider.position"} <= units["Asserted quantities (m)"]
    assert {"box.vel.z", "door.vel.x"} <= units["Asserted quantities (m/s)"]


def _plots(data: dict[str, Any]) -> dict[str, list[dict[str, Any]]]:
    """Each Plot panel's title -> its paths."""
    return {c["foxglovePanelTitle"]: c["paths"] for k, c in data["configById"].items() if k.startswith("Plot!")}


def test_every_asserted_quantity_is_plotted_robots_and_every_copy_of_an_array_included() -> None:
    """Issue 30: the robots' asserted hand and joint, box_pile's top crate (the old 12-series cut dropped it)."""
    kuka = _plots(layout(layout_spec(load_files([ROOT / "scenarios" / "robots" / "kuka_arm.yaml"], None, True))))
    assert [p["label"] for p in kuka["Asserted quantities (m)"]] == [
        "arm.lbr_iiwa_link_7.pos.z", "arm.lbr_iiwa_link_7.pos.x", "arm.lbr_iiwa_link_7.pos.y"]  # fmt: skip
    assert kuka["Asserted quantities (m)"][1]["value"] == (
        '/tf.transforms[:]{child_frame_id=="arm.lbr_iiwa_link_7"}.translation.x')
    assert [p["value"] for p in kuka["Asserted quantities (rad)"]] == ["/joints.arm.lbr_iiwa_joint_2.position"]
    pile = _plots(layout(layout_spec(load_files([ROOT / "scenarios" / "box_pile.yaml"], None, True))))
    heights = [p["label"] for p in pile["Asserted quantities (m)"] if p["label"].endswith(".pos.z")]
    assert heights == [f"crate_{k}.pos.z" for k in range(5)]  # count 5: every crate, the top one included
    many = _plots(layout(layout_spec(load_files([ROOT / "scenarios" / "box_pile.yaml"], None, True,
                                                (("params.count", 30),)))))  # fmt: skip
    assert len([p for p in many["Asserted quantities (m)"] if p["label"].endswith(".pos.z")]) == 30


def test_a_scenario_whose_assertions_read_no_height_still_plots_one() -> None:
    spec = layout_spec(load_files([ROOT / "scenarios" / "conformance" / "04_slider_motor.yaml"], None, True))
    assert any(p.value.startswith("/tf.transforms") and p.value.endswith(".translation.z") for p in spec.plots)


def test_scenario_layout_prints_or_writes_it_and_run_writes_it_beside_the_traces(tmp_path: Path) -> None:
    printed = _cli("layout", "scenarios/factory_intervals.yaml")
    assert printed.returncode == 0, printed.stderr
    data = json.loads(printed.stdout)
    assert _panels(data) == set(data["configById"])
    written = _cli("layout", "scenarios/factory_intervals.yaml", "--out", str(tmp_path / "layout"))
    assert written.returncode == 0 and json.loads((tmp_path / "layout" / tf.LAYOUT_FILE).read_text()) == data
    run = _cli("run", "scenarios/factory_intervals.yaml", "--out", str(tmp_path / "traces"), "--quiet")
    assert run.returncode == 0, run.stderr
    assert json.loads((tmp_path / "traces" / tf.LAYOUT_FILE).read_text()) == layout(
        layout_spec(load_files([ROOT / "scenarios" / "factory_intervals.yaml"], None, False))
    )
    (tmp_path / "file").write_text("not a folder")
    bad = _cli("layout", "scenarios/factory_intervals.yaml", "--out", str(tmp_path / "file"))
    assert bad.returncode == 2 and "cannot write" in bad.stderr and "Traceback" not in bad.stderr


def test_two_scenarios_run_into_one_folder_keep_both_layouts(tmp_path: Path) -> None:
    for file in ("scenarios/factory_intervals.yaml", "scenarios/box_pile.yaml"):
        done = _cli("run", file, "--out", str(tmp_path), "--quiet")
        assert done.returncode == 0, done.stderr
    for name, file in (("factory-intervals", "factory_intervals.yaml"), ("box-pile", "box_pile.yaml")):
        own = json.loads((tmp_path / tf.scenario_layout_file(name)).read_text())
        assert own == layout(layout_spec(load_files([ROOT / "scenarios" / file], None, False))), name
    combined = json.loads((tmp_path / tf.LAYOUT_FILE).read_text())  # the last command's scenarios
    assert combined == layout(layout_spec(load_files([ROOT / "scenarios" / "box_pile.yaml"], None, False)))


def test_the_3d_panel_is_framed_on_the_bodies_and_its_grid_is_sized_to_them() -> None:
    """The camera's target is the centre of the box around the bodies' spheres and its distance holds the
    sphere around that box in a 45-degree field of view (radius / sin(22.5 deg), 1 m radius at least); the
    grid is a square of 1, 2 or 5 x 10^k m at least twice the horizontal extent (2 m at least), in 10 cells,
    centred under the bodies on a cell corner."""
    # a 12 m x 3 m row of unit spheres at z = 1: box x -0.5..12.5 (13 m), y -0.5..0.5, z 0.5..1.5
    row = LayoutSpec([], (), [((x, 0.0, 1.0), 0.5) for x in range(13)])
    scene = layout(row)["configById"]["3D!scene"]
    camera, grid = scene["cameraState"], scene["layers"]["grid"]
    assert camera["targetOffset"] == [6.0, 0.0, 1.0]
    radius = math.dist((-0.5, -0.5, 0.5), (12.5, 0.5, 1.5)) / 2
    # the layout uses 2.6 r, 1 / sin(22.5 deg) = 2.613 to two digits: 0.5 % closer than the exact fit
    assert camera["distance"] == pytest.approx(radius / math.sin(math.radians(22.5)), rel=0.01)
    assert (grid["layerId"], grid["visible"], grid["size"], grid["divisions"]) == ("foxglove.Grid", True, 50, 10)
    assert grid["position"] == [5.0, 0.0, 0]  # 6 m rounded to the 5 m cells
    # the KUKA arm: less than 1 m across at its start, so the 2 m floor: 5 m in 0.5 m cells, camera 2.6 m away
    kuka = layout(layout_spec(load_files([ROOT / "scenarios" / "robots" / "kuka_arm.yaml"], None, True)))
    scene = kuka["configById"]["3D!scene"]
    assert (scene["layers"]["grid"]["size"], scene["cameraState"]["distance"]) == (5, 2.6)
