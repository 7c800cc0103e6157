"""Joint dynamics as the model files and the scenario state them (docs/semantics.md, "Joint dynamics"):
URDF `<dynamics>` and `<limit effort velocity>`, MJCF's compiled joint (defaults applied), the scenario's
`dynamics:` overrides, and what is refused at its line."""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.types import Capability, JointDynamics
from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.language.robot_desc import ModelFileError
from runner.language.urdf import load_urdf

URDF = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="upper"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
  </inertial></link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="{effort}" velocity="0"/>
    <dynamics damping="{damping}" friction="0.2"/>
  </joint>
</robot>
"""


def _urdf(tmp_path: Path, damping: str = "0.5", effort: str = "30") -> Path:
    path = tmp_path / "arm.urdf"
    path.write_text(URDF.format(damping=damping, effort=effort))
    return path


def test_urdf_dynamics_and_limits_are_read(tmp_path: Path) -> None:
    desc = load_urdf(_urdf(tmp_path), None, True, False)
    joint = next(j for j in desc.joints if j.name == "shoulder")
    # velocity="0" is no limit (files write 0 for "not stated")
    assert joint.dynamics == JointDynamics(damping=0.5, frictionloss=0.2, effort=30.0, velocity=None)


def test_a_negative_damping_is_refused_at_its_joint(tmp_path: Path) -> None:
    with pytest.raises(ModelFileError, match="joint `shoulder`: damping -1 is not a number >= 0") as found:
        load_urdf(_urdf(tmp_path, damping="-1"), None, True, False)
    assert found.value.line == 6


def _scenario(tmp_path: Path, joint: str) -> Path:
    _urdf(tmp_path)
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: s\nworld: {dt: 0.01, duration: 0.1}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [9, 9, 0]}\n"
        f"robots:\n  r: {{urdf: arm.urdf, fixed: true, joints: {{shoulder: {joint}}}}}\n"
    )
    return path


def test_the_scenario_replaces_each_field_it_gives(tmp_path: Path) -> None:
    world = build_program(load_scenario(_scenario(tmp_path, "{dynamics: {damping: 2, velocity: 3}}"))).world
    assert world.joints[0].dynamics == JointDynamics(damping=2.0, frictionloss=0.2, effort=30.0, velocity=3.0)
    assert world.joints[0].motor is None  # the runner commands the joint's motor; every adapter has one


def test_effort_and_velocity_cap_a_motor(tmp_path: Path) -> None:
    given = "{motor: {vel: 9, fmax: 100}, dynamics: {velocity: 2}}"
    world = build_program(load_scenario(_scenario(tmp_path, given))).world
    motor = world.joints[0].motor
    assert motor is not None and (motor.vel, motor.fmax) == (2.0, 30.0)


def test_dynamics_on_a_ball_joint_is_refused_at_the_field(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: s\nworld: {dt: 0.01, duration: 0.1}\n"
        "bodies:\n  a: {sphere: 0.1, mass: 1}\n"
        "joints:\n  j: {type: ball, bodies: [a, environment], dynamics: {damping: 1}}\n"
    )
    with pytest.raises(ScenarioValidationError, match="`dynamics` is defined for sliders and hinges"):
        load_scenario(path)


MJCF = """<mujoco>
  <compiler angle="radian"/>
  <default><joint damping="0.3" armature="0.01"/></default>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" stiffness="5" springref="0.2" frictionloss="0.1"/>
      <geom type="capsule" fromto="0 0 0 .3 0 0" size=".02"/>
      <body name="b" pos=".3 0 0">
        <joint name="ball" type="ball"/>
        <geom type="sphere" size=".05"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_mjcf_dynamics_as_mujoco_compiled_them(tmp_path: Path) -> None:
    pytest.importorskip("mujoco", reason="reading MJCF needs MuJoCo's compiler (the `mujoco` extra)")
    from runner.language.mjcf import load_mjcf

    path = tmp_path / "m.xml"
    path.write_text(MJCF)
    desc = load_mjcf(path)
    hinge = next(j for j in desc.joints if j.name == "hinge")
    assert hinge.dynamics == JointDynamics(damping=0.3, frictionloss=0.1, armature=0.01, stiffness=5.0, springref=0.2)
    needs = {n.capability: n.line for n in desc.needs}
    # the ball's damping and armature from the default class; the hinge's armature and spring
    assert needs == {"joint:armature": 6, "joint:stiffness": 6, "joint:ball-dynamics": 9}
    assert {Capability(c) for c in needs} <= set(Capability)
