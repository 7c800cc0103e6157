"""`scenario inspect SCENARIO`: each robot's links (mass), joints (kind, limits, axis) and actuators, checked
against what tools we did not write read from the same files: yourdfpy for the KUKA arm's URDF, the XML
itself for dm_control's manipulator's `<actuator>` list. Names as the file spells them (spirit40's `8`)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from runner.language.robot_desc import data_root
from tests.paths import ROOT

DATA = data_root("@pybullet_data")[0]  # type: ignore[index]
KUKA_SCENARIO = ROOT / "scenarios" / "robots" / "kuka_arm.yaml"
_KINDS = {"revolute": "hinge", "continuous": "hinge", "prismatic": "slider", "fixed": "fixed"}


def _inspect(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "runner", "inspect", *args], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)  # fmt: skip


def _rows(text: str) -> list[list[str]]:
    """The cells of rich's tables in ``text``, a wrapped row's continuation lines joined to it."""
    rows: list[list[str]] = []
    for line in text.splitlines():
        if "│" not in line:
            continue
        cells = [cell.strip() for cell in line.split("│")[1:-1]]
        if rows and cells and not cells[0] and len(cells) == len(rows[-1]):
            rows[-1] = [f"{a} {b}".strip() for a, b in zip(rows[-1], cells, strict=True)]
        else:
            rows.append(cells)
    return rows


def _json(path: Path) -> dict[str, Any]:
    done = _inspect(str(path), "--json")
    assert done.returncode == 0, done.stderr
    return dict(json.loads(done.stdout))


def test_the_kuka_arm_as_yourdfpy_reads_it() -> None:
    import yourdfpy

    robot = _json(KUKA_SCENARIO)["robots"]["arm"]
    urdf = yourdfpy.URDF.load(str(DATA / "kuka_iiwa" / "model.urdf"), load_meshes=False)
    assert [link["name"] for link in robot["links"]] == [link.name for link in urdf.robot.links]
    for link in robot["links"]:
        assert link["mass"] == urdf.link_map[link["name"]].inertial.mass
    assert [j["name"] for j in robot["joints"]] == [j.name for j in urdf.robot.joints]
    for j in robot["joints"]:
        joint = urdf.joint_map[j["name"]]
        assert j["kind"] == _KINDS[joint.type] and (j["parent"], j["child"]) == (joint.parent, joint.child)
        if joint.type == "revolute":  # the limits as the file says them (the arm starts at 0, inside them)
            assert (j["lower"], j["upper"], j["unit"]) == (joint.limit.lower, joint.limit.upper, "rad")
            # the axis in the model frame at the zero configuration: the joint frame's rotation times its axis
            rotation = urdf.get_transform(joint.child, urdf.base_link)[:3, :3]
            assert np.allclose(j["axis"], rotation @ joint.axis, atol=1e-12)
    assert robot["actuators"] == []


def test_names_as_the_file_spells_them_and_limits_in_text(tmp_path: Path) -> None:
    scenario = tmp_path / "s.yaml"
    scenario.write_text("schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 0.1}\n"
                        "bodies: {ground: {plane: {}, motion: static}}\n"
                        'robots: {dog: {urdf: "@pybullet_data/quadruped/spirit40.urdf"}}\n')  # fmt: skip
    done = subprocess.run([sys.executable, "-m", "runner", "inspect", str(scenario)], capture_output=True,
                          text=True, cwd=ROOT, timeout=300, env={**os.environ, "COLUMNS": "200"})  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = _rows(done.stdout)
    # spirit40.urdf: <joint name="8" type="revolute"> body -> hip0, axis 1 0 0, limits -0.707 .. 0.707
    # ... and <limit effort="40" velocity="30">
    assert ["8", "hinge", "body", "hip0", "-0.707 .. 0.707 rad", "1 0 0", "effort 40, velocity 30"] in rows
    assert ["jtoe0", "fixed", "lower0", "toe0", "", "", ""] in rows
    assert ["body", "5.75"] in rows  # <link name="body"> <mass value="5.75"/>
    assert "dog: no actuators in the model file" in done.stdout


def test_mjcf_actuators_as_the_file_lists_them(tmp_path: Path) -> None:
    dm_control = pytest.importorskip("dm_control", reason="dm_control's suite is a test dependency (dm-control)")
    suite = Path(dm_control.__file__).parent / "suite"
    (tmp_path / "common").mkdir()
    for file in (suite / "common").glob("*.xml"):
        (tmp_path / "common" / file.name).write_bytes(file.read_bytes())
    (tmp_path / "manipulator.xml").write_bytes((suite / "manipulator.xml").read_bytes())
    scenario = tmp_path / "s.yaml"
    scenario.write_text("schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 0.1}\n"
                        "bodies: {ground: {plane: {}, motion: static}}\nrobots: {hand: {mjcf: manipulator.xml}}\n")
    robot = _json(scenario)["robots"]["hand"]
    listed = [e for e in ET.parse(tmp_path / "manipulator.xml").getroot().iter("actuator") for e in e]
    assert [(a["name"], a["kind"], a["joint"]) for a in robot["actuators"]] == [
        (e.get("name"), e.tag, e.get("joint")) for e in listed
    ]
    assert "pinch site" in [link["name"] for link in robot["links"]]
    shoulder = next(j for j in robot["joints"] if j["name"] == "arm_shoulder")
    # <joint name="arm_shoulder" range="-160 160"/> in degrees (the file's <compiler> default), axis 0 -1 0
    assert shoulder["lower"] == pytest.approx(np.radians(-160), abs=1e-12)
    assert shoulder["upper"] == pytest.approx(np.radians(160), abs=1e-12)
    assert shoulder["axis"] == pytest.approx([0, -1, 0], abs=1e-12)


def test_json_is_for_scenarios_and_a_broken_scenario_is_located(tmp_path: Path) -> None:
    trace = tmp_path / "t.mcap"
    trace.write_bytes(b"")
    done = _inspect(str(trace), "--json")
    assert done.returncode == 2 and "--json and --variant are for a scenario file" in done.stderr + done.stdout
    bad = tmp_path / "bad.yaml"
    bad.write_text("schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 0.1}\n"
                   "bodies: {ground: {plane: {}, motion: static}}\nrobots: {dog: {urdf: missing.urdf}}\n")
    done = _inspect(str(bad))
    assert done.returncode == 2 and "Traceback" not in done.stderr and f"{bad}:5:" in done.stderr + done.stdout


def test_joint_dynamics_and_mimic_as_yourdfpy_reads_them(tmp_path: Path) -> None:
    """The Franka Panda's `<limit effort velocity>`, `<dynamics>` and the finger's `<mimic>`, in the JSON and
    the text, against yourdfpy's reading of the same file (issue 28: inspect lists what the file declares)."""
    import yourdfpy

    scenario = tmp_path / "panda.yaml"
    scenario.write_text("schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 0.1}\n"
                        "bodies: {ground: {plane: {}, motion: static}}\n"
                        'robots: {panda: {urdf: "@pybullet_data/franka_panda/panda.urdf", fixed: true}}\n')  # fmt: skip
    robot = _json(scenario)["robots"]["panda"]
    urdf = yourdfpy.URDF.load(str(DATA / "franka_panda" / "panda.urdf"), load_meshes=False)
    mimics = 0
    for j in robot["joints"]:
        joint = urdf.joint_map[j["name"]]
        expected: dict[str, float] = {}
        if joint.limit is not None and joint.type != "fixed":
            expected |= {k: float(v) for k in ("effort", "velocity") if (v := getattr(joint.limit, k)) is not None}
        if joint.dynamics is not None:
            expected |= {k: float(v) for k, attr in (("damping", "damping"), ("frictionloss", "friction"))
                         if (v := getattr(joint.dynamics, attr)) is not None}  # fmt: skip
        assert j["dynamics"] == {k: v for k, v in expected.items() if v != 0.0}, j["name"]
        if joint.mimic is None:
            assert j["mimic"] is None
        else:
            mimics += 1
            assert j["mimic"] == {"leader": joint.mimic.joint, "multiplier": joint.mimic.multiplier or 1.0,
                                  "offset": joint.mimic.offset or 0.0}  # fmt: skip
    assert mimics == 1  # panda_finger_joint2 follows panda_finger_joint1
    done = subprocess.run([sys.executable, "-m", "runner", "inspect", str(scenario)], capture_output=True,
                          text=True, cwd=ROOT, timeout=300, env={**os.environ, "COLUMNS": "300"})  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = _rows(done.stdout)
    follower = next(r for r in rows if r and r[0] == "panda_finger_joint2")
    assert follower[-1] == "effort 20, velocity 0.2; = 1 x panda_finger_joint1", follower


def test_a_legacy_mjcf_files_upgrade_is_listed_as_notes(tmp_path: Path) -> None:
    """pybullet_data's hopper is in MJCF's legacy dialect (global coordinates, a missing material): `inspect`
    says what the upgrade did (runner.language.mjcf_legacy), in the JSON and in the text."""
    scenario = tmp_path / "s.yaml"
    scenario.write_text("schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 0.1}\n"
                        "bodies: {ground: {plane: {}, motion: static}}\n"
                        "robots: {hop: {mjcf: '@pybullet_data/mjcf/hopper.xml', pos: [0, 0, 0.1]}}\n")  # fmt: skip
    notes = _json(scenario)["robots"]["hop"]["notes"]
    assert len(notes) == 2 and 'coordinate="global"' in notes[0] and "material `geom`" in notes[1]
    done = _inspect(str(scenario))
    assert done.returncode == 0 and "hop: note: legacy MJCF" in done.stdout.replace("\n", " "), done.stdout
