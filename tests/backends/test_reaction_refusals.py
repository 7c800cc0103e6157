"""Reading a joint's reaction where an engine cannot give one joint's wrench is refused before the run, by
`scenario validate --backend` as by `run` (exit 2, the joint and the reason named): on MuJoCo, a joint of an
MJCF body moved by several joints (cfrc_int is one wrench per body)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

MODEL = """<mujoco model="two"><worldbody><body name="b" pos="0 0 1">
<joint name="h" type="hinge" axis="0 1 0"/><joint name="s" type="slide" axis="0 0 1"/>
<geom type="sphere" size="0.05" mass="1"/></body></worldbody></mujoco>"""
SCENARIO = """schema_version: 1
scenario: two
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}}
bodies:
  ground: {{plane: {{}}, motion: static}}
robots:
  r: {{mjcf: two.xml}}
assertions:
  - {{name: a, at: end, value: {value}, near: 0, tol: 1e9}}
"""


@pytest.mark.parametrize("command", ["validate", "run"])
def test_mujoco_refuses_the_reaction_of_one_of_several_joints_of_a_body(tmp_path: Path, command: str) -> None:
    pytest.importorskip("mujoco")
    (tmp_path / "two.xml").write_text(MODEL)
    path = tmp_path / "two.yaml"
    path.write_text(SCENARIO.format(value="r.h.reaction.force.z"))
    args = [sys.executable, "-m", "runner", command, str(path), "--backend", "mujoco"]
    done = subprocess.run([*args, *(["--out", str(tmp_path / "out")] if command == "run" else [])],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    assert "the reaction of joint `r.h`" in done.stderr and "one wrench per body" in done.stderr
    path.write_text(SCENARIO.format(value="r.b.kinetic_energy"))  # what does not need the engine still runs
    validate = [sys.executable, "-m", "runner", "validate", str(path), "--backend", "mujoco"]
    assert subprocess.run(validate, capture_output=True, timeout=120).returncode == 0
