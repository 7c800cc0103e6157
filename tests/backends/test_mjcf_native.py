"""An unmodified MJCF model run with its own options (`world.options: model`) reproduces MuJoCo's own
`mj_step` on the same file (issue 28, item 3).

The reference is `mujoco.MjModel.from_xml_path(file)` stepped with `mujoco.mj_step` from `MjData`'s default
state, for 2 s. The scenario runs the same file through the runner (load, compile, the mujoco backend's
`MjSpec.from_file` plus the scenario's parts: a static marker far away and the robot's placement body, which
own no degree of freedom and touch nothing). Every hinge and slide position and every link's pose must
agree to 1e-9 (rad, m): the two are the same engine integrating the same model from the same state with the
same step, so they agree to rounding; 1e-9 leaves room for nothing else (a changed option, a changed
contact parameter, a missing actuator or tendon, a different body order would all show at 1e-6 or more
within 2 s on these models, chaotic ones included).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from backends.registry import create_backend
from runner.compile.program import build_program
from runner.language.load import load_scenario

mujoco = pytest.importorskip("mujoco", reason="engine not installed: pip install 'physics-scenarios[mujoco]'")

TOL = 1e-9  # rad, m: rounding only (module docstring)
DURATION = 2.0
#: pybullet_data's MJCF files that MuJoCo 4 accepts (the others use attributes MuJoCo dropped): pendulums
#: with tendons and actuators, an arm, a free-floating walker with contacts.
PYBULLET = ("inverted_pendulum", "inverted_double_pendulum", "reacher", "pusher", "ant")
#: dm_control's suite (its files `<include>` ./common/*.xml): planar walkers on several joints per body.
DM_CONTROL = ("cartpole", "pendulum", "acrobot", "cheetah", "hopper", "walker")


def _pybullet_mjcf() -> Path:
    import pybullet_data

    return Path(pybullet_data.getDataPath()) / "mjcf"


def _dm_suite() -> Path:
    dm_control = pytest.importorskip("dm_control", reason="dm_control's suite is a test dependency (dm-control)")
    return Path(dm_control.__file__).parent / "suite"


def _scenario(folder: Path, model: str) -> Path:
    reference = mujoco.MjModel.from_xml_path(str(folder / f"{model}.xml"))
    g = [float(c) for c in reference.opt.gravity]
    path = folder / f"{model}.native.yaml"
    path.write_text(
        "schema_version: 1\nscenario: native\n"
        f"world: {{dt: {float(reference.opt.timestep)!r}, duration: {DURATION}, gravity: {g}, options: model}}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [100, 100, 0]}\n"
        f"robots:\n  r: {{mjcf: {model}.xml}}\n"
    )
    return path


def _compare(folder: Path, model: str) -> None:
    file = folder / f"{model}.xml"
    loaded = load_scenario(_scenario(folder, model))
    world = build_program(loaded).world
    m = mujoco.MjModel.from_xml_path(str(file))
    d = mujoco.MjData(m)
    steps = round(DURATION / m.opt.timestep)
    joints = {f"r.{m.joint(j).name}": j for j in range(m.njnt) if m.joint(j).name}
    hinge_slide = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    rated = [(k, joints[spec.name]) for k, spec in enumerate(world.joints)
             if spec.name in joints and int(m.jnt_type[joints[spec.name]]) in hinge_slide]  # fmt: skip
    assert rated, f"{model}: no hinge or slide compared"
    links = [(world.body_index(f"r.{m.body(b).name}"), b) for b in range(1, m.nbody) if m.body(b).name]
    with create_backend("mujoco", world) as sim:
        for step in range(steps):
            sim.step()
            mujoco.mj_step(m, d)
            if step % 50 and step != steps - 1:
                continue
            ours = sim.joint_states().position
            for k, j in rated:
                q = float(d.qpos[m.jnt_qposadr[j]])
                assert abs(ours[k] - q) <= TOL, (
                    f"{model}: joint {world.joints[k].name} at step {step + 1}: {ours[k]} vs {q}"
                )
            mujoco.mj_kinematics(m, d)
            states = sim.body_states()
            for i, b in links:
                assert np.allclose(states.pos[i], d.xpos[b], rtol=0, atol=TOL), f"{model}: body {m.body(b).name}"
                assert np.allclose(states.quat[i], d.xquat[b], rtol=0, atol=TOL), f"{model}: body {m.body(b).name}"


@pytest.mark.parametrize("model", PYBULLET)
def test_pybullet_data_mjcf_reproduces_mj_step(tmp_path: Path, model: str) -> None:
    shutil.copy(_pybullet_mjcf() / f"{model}.xml", tmp_path)
    _compare(tmp_path, model)


@pytest.mark.parametrize("model", DM_CONTROL)
def test_dm_control_suite_reproduces_mj_step(tmp_path: Path, model: str) -> None:
    suite = _dm_suite()
    shutil.copytree(suite / "common", tmp_path / "common")
    shutil.copy(suite / f"{model}.xml", tmp_path)
    _compare(tmp_path, model)


def test_scenario_servo_and_limits_act_on_a_files_joints(tmp_path: Path) -> None:
    """With the scenario's options, a servo on a joint of the file drives it (the backend's motor tendon wraps
    the file's joint across the attached specs) and `limits` replace the file's range. The servo's velocity
    motor removes all but 1e-4 of its rate error per step (MOTOR_IMPEDANCE), so after 2 s at gain 20 /s the
    hinge sits on its target far inside 1e-3 rad."""
    shutil.copy(_pybullet_mjcf() / "inverted_double_pendulum.xml", tmp_path)
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: servo\nworld: {dt: 0.01, duration: 2}\n"
        "bodies:\n  marker: {box: [0.05, 0.05, 0.05], motion: static, pos: [50, 50, 0]}\n"
        "robots:\n  r:\n    mjcf: inverted_double_pendulum.xml\n"
        "    joints: {hinge: {servo: {target: 0.3, gain: 20, fmax: 500}}, slider: {limits: [-0.5, 0.5]}}\n"
        "assertions:\n  - {name: on-target, at: end, value: r.hinge.position, near: 0.3, tol: 1e-3}\n"
    )
    from runner.sim.run import run_loaded

    result = run_loaded(load_scenario(path), "mujoco", None)
    assert "passed" in str(result.status), result
    world = build_program(load_scenario(path)).world
    with create_backend("mujoco", world) as sim:
        model = sim._m  # type: ignore[attr-defined]  # white box: the compiled model's range of the file's slider
        assert list(model.jnt_range[model.joint("slider").id]) == [-0.5, 0.5]
