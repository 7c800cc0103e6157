"""Drake's own URDF parser as the import reference of the drake backend (issue 32, "robots through Drake's own
parsers").

The runner reads a URDF (runner/language/urdf.py) and the drake adapter builds its links and joints from the
compiled world (docs/backends/drake.md, "Robots"). Here the same file goes through
``pydrake.multibody.parsing.Parser`` into a MultibodyPlant of its own, its root welded at the scenario's pose
(tilted, hpr 20, 30, 10 degrees, so that no axis is a world axis by accident), and what the adapter's plant
holds (``imported_model()``: read back from Drake) must be what Drake's parser makes of the file: every moving
link's mass, principal moments about its COM and COM in the link frame, every joint's type, world axis at the
zero configuration and position limits. Both are float64 and differ only by the rounding of the pose
compositions (the runner's quaternions against Drake's RollPitchYaw and frame chain): 1e-9, relative to each
value's scale. Then the two swing (``test_the_adapters_robot_swings_as_drakes_parser_builds_it``): the same
joint positions to rounding at every step. Not compared: joint damping, which Drake's parser puts on the joint
(kuka 0.5 N m s/rad) and the runner realises itself beside any engine (docs/robots.md, "Joint dynamics"), so
the adapter's joint holds 0.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from backends.registry import create_backend, is_installed
from backends.types import ImportedModel, JointKind
from runner.compile.program import build_program
from runner.language.hpr import hpr_to_quat
from runner.language.load import load_scenario

if not is_installed("drake"):
    pytest.skip("engine not installed: pip install 'physics-scenarios[drake]'", allow_module_level=True)

TOL = 1e-9  # float64 rounding of pose compositions (module docstring)
HPR = (20.0, 30.0, 10.0)
#: pybullet_data URDFs that Drake's parser reads and whose zero configuration is inside their limits (a1 and
#: laikago start outside them: the runner counts stops from the clamped start, docs/robots.md). Drake's parser
#: refuses others the runner reads: humanoid (`spherical` joints), husky (`$(optenv ...)` in a number), xarm6
#: (two transmissions naming one actuator), biped2d (a joint's lower limit above its upper: Drake aborts).
MODELS = (
    "kuka_iiwa/model.urdf",
    "cartpole.urdf",
    "quadruped/quadruped.urdf",
    "franka_panda/panda.urdf",
    "r2d2.urdf",
    "racecar/racecar.urdf",
)
_KINDS = {"revolute": JointKind.HINGE, "prismatic": JointKind.SLIDER, "weld": JointKind.FIXED}


def _adapter(tmp_path: Path, model: str) -> ImportedModel:
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: parser\nworld: {dt: 0.01, duration: 0.1}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [100, 100, 0]}\n"
        f"robots:\n  r: {{urdf: '@pybullet_data/{model}', fixed: true, pos: [0, 0, 1], hpr: {list(HPR)}}}\n"
    )
    with create_backend("drake", build_program(load_scenario(path)).world) as sim:
        imported = sim.imported_model()
    assert imported is not None
    return imported


def _drake_parser(file: Path) -> tuple[dict[str, tuple[float, Any, Any]], dict[str, tuple[JointKind, Any, Any, Any]]]:
    """Per link: (mass, principal moments about the COM, COM in the link frame); per joint: (kind, world axis,
    lower, upper), as Drake's Parser builds the file with its root welded at the scenario's pose."""
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RigidTransform
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)  # no SceneGraph: the collision meshes' formats play no part
    (instance,) = Parser(plant).AddModels(file)
    root = plant.get_body(plant.GetBodyIndices(instance)[0])
    w, x, y, z = hpr_to_quat(HPR)
    origin: Any = np.array([0.0, 0.0, 1.0])  # the scenario's pos (pydrake's stubs take no typed array)
    plant.WeldFrames(plant.world_frame(), root.body_frame(), RigidTransform(Quaternion(w, x, y, z), origin))
    plant.Finalize()
    context = plant.CreateDefaultContext()
    links: dict[str, tuple[float, Any, Any]] = {}
    for index in plant.GetBodyIndices(instance):
        rigid = plant.get_body(index)
        inertia = rigid.default_spatial_inertia()
        com = inertia.get_com()
        central = inertia.Shift(com).CalcRotationalInertia().CopyToFullMatrix3()
        links[rigid.name()] = (float(rigid.default_mass()), np.linalg.eigvalsh(central), np.asarray(com))
    joints: dict[str, tuple[JointKind, Any, Any, Any]] = {}
    for index in plant.GetJointIndices(instance):
        joint = plant.get_joint(index)
        kind = _KINDS.get(joint.type_name())
        if kind in (JointKind.HINGE, JointKind.SLIDER):
            local = joint.revolute_axis() if kind is JointKind.HINGE else joint.translation_axis()
            axis = joint.frame_on_parent().CalcPoseInWorld(context).rotation().matrix() @ np.asarray(local)
            lo, hi = float(joint.position_lower_limits()[0]), float(joint.position_upper_limits()[0])
            joints[joint.name()] = (kind, axis, lo if np.isfinite(lo) else None, hi if np.isfinite(hi) else None)
        elif kind is JointKind.FIXED:
            joints[joint.name()] = (kind, None, None, None)
    return links, joints


def _continuous_limits(file: Path) -> dict[str, tuple[float, float]]:
    """The file's continuous joints that carry `<limit lower upper>`: Drake's parser applies those limits, the
    URDF specification (and the runner, PyBullet, MuJoCo and DART with it) gives a continuous joint none
    (../shared/notes/robot-models.md, 3.1): the one difference expected here (r2d2's head, racecar's steering)."""
    out = {}
    for joint in ET.parse(file).getroot().iter("joint"):
        limit = joint.find("limit")
        if joint.get("type") == "continuous" and limit is not None and "lower" in limit.attrib:
            out[str(joint.get("name"))] = (float(limit.attrib["lower"]), float(limit.attrib.get("upper", 0.0)))
    return out


@pytest.mark.parametrize("model", MODELS)
def test_the_adapters_plant_is_what_drakes_parser_makes_of_the_file(tmp_path: Path, model: str) -> None:
    import pybullet_data

    file = Path(pybullet_data.getDataPath()) / model
    built = _adapter(tmp_path, model)
    links, joints = _drake_parser(file)
    continuous = _continuous_limits(file)
    assert built.bodies and built.joints
    for body in built.bodies:
        mass, moments, com = links[body.name.removeprefix("r.")]
        scale = max(float(np.max(moments)), 1e-12)
        assert body.mass == pytest.approx(mass, rel=TOL), body.name
        assert np.allclose(body.inertia, moments, rtol=0.0, atol=TOL * scale), (body.name, body.inertia, moments)
        assert np.allclose(body.com, com, rtol=0.0, atol=TOL), (body.name, body.com, com)
    compared = 0
    for joint in built.joints:
        kind, axis, lo, hi = joints[joint.name.removeprefix("r.")]
        assert joint.kind is kind, joint.name
        if axis is not None:
            assert joint.axis is not None and np.allclose(joint.axis, axis, rtol=0.0, atol=TOL), (
                joint.name,
                joint.axis,
                axis,
            )
            if joint.name.removeprefix("r.") in continuous:
                assert (joint.lo, joint.hi) == (None, None)
                assert (lo, hi) == continuous[joint.name.removeprefix("r.")]
                compared += 1
                continue
            assert (joint.lo is None) == (lo is None) and (joint.hi is None) == (hi is None), joint.name
            if lo is not None and hi is not None:
                assert (joint.lo, joint.hi) == pytest.approx((lo, hi), abs=TOL), joint.name
            compared += 1
    assert compared > 0


#: Files whose links do not touch each other while they swing for SWING seconds (the adapter keeps
#: self-collision on; the reference plant has no SceneGraph) and without `<mimic>`, which the runner reads past
#: (docs/robots.md) and Drake's parser makes a coupler constraint: the franka panda's fingers, whose coupling moves
#: its wrist 6e-5 rad from the reference after one step.
SWING_MODELS = ("kuka_iiwa/model.urdf", "cartpole.urdf", "quadruped/quadruped.urdf", "r2d2.urdf")
SWING, SWING_DT = 0.8, 1.0 / 240.0


@pytest.mark.parametrize("model", SWING_MODELS)
def test_the_adapters_robot_swings_as_drakes_parser_builds_it(tmp_path: Path, model: str) -> None:
    """The tilted robot (root welded, hpr 20, 30, 10) swings under gravity for 0.8 s on the adapter (the backend
    alone: no runner damping, motors off) and on a plant Drake's Parser built from the same file, both discrete
    SAP plants at 1/240 s, the parser's `<dynamics damping>` set to 0. The same engine integrates the same tree
    with the same inertias, so each joint agrees to rounding (1e-9 rad or m) at every step, while the joints
    move by up to 2.9 rad (kuka; asserted to move more than 1e-3); a wrong inertia, axis or frame shows at 1e-4
    within a few steps. Each file starts at its zero configuration, inside its limits (no start clamp)."""
    import pybullet_data
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RigidTransform
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import DiscreteContactApproximation, MultibodyPlant

    path = tmp_path / "s.yaml"
    path.write_text(
        f"schema_version: 1\nscenario: swing\nworld: {{dt: {SWING_DT!r}, duration: {SWING}}}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [100, 100, 0]}\n"
        f"robots:\n  r: {{urdf: '@pybullet_data/{model}', fixed: true, pos: [0, 0, 1], hpr: {list(HPR)}}}\n"
    )
    world = build_program(load_scenario(path)).world
    plant = MultibodyPlant(SWING_DT)
    plant.set_discrete_contact_approximation(DiscreteContactApproximation.kSap)
    (instance,) = Parser(plant).AddModels(Path(pybullet_data.getDataPath()) / model)
    root = plant.get_body(plant.GetBodyIndices(instance)[0])
    w, x, y, z = hpr_to_quat(HPR)
    origin: Any = np.array([0.0, 0.0, 1.0])
    plant.WeldFrames(plant.world_frame(), root.body_frame(), RigidTransform(Quaternion(w, x, y, z), origin))
    coordinates = {}
    for index in plant.GetJointIndices(instance):
        joint = plant.get_joint(index)
        if joint.num_velocities() == 1:
            joint.set_default_damping(0.0)
            coordinates[f"r.{joint.name()}"] = joint
    plant.Finalize()
    context = plant.CreateDefaultContext()
    compared = [(k, coordinates[j.name]) for k, j in enumerate(world.joints) if j.name in coordinates]
    assert len(compared) == len(coordinates) > 0

    def reference(joint: Any) -> float:
        return float(joint.get_angle(context) if joint.type_name() == "revolute" else joint.get_translation(context))

    moved = 0.0
    with create_backend("drake", world) as sim:
        for _ in range(round(SWING / SWING_DT)):
            sim.step()
            plant.ExecuteForcedEvents(context, publish=False)
            position = sim.joint_states().position
            for k, joint in compared:
                assert position[k] == pytest.approx(reference(joint), abs=TOL), (world.joints[k].name, sim.steps)
                moved = max(moved, abs(reference(joint)))
    assert moved > 1e-3
