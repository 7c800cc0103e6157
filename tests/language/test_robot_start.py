"""A robot's start state (`initial:`) and robot parts in actions (issue 29, items 1 and 3): a start is placed
by forward kinematics, checked against the joints' limits (exit 2 at the value, the joint and its limits
named), MJCF keyframes are read, and `force`, `impulse`, `apply`, `motor`, `reset` and `contact:` take
`<robot>.<part>` names."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from runner.compile.program import build_program
from runner.compile.robot_start import link_motions
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from tests.paths import ROOT

KUKA = "@pybullet_data/kuka_iiwa/model.urdf"


def _write(folder: Path, robot: str, extra: str = "", name: str = "s.yaml") -> Path:
    path = folder / name
    path.write_text(
        "schema_version: 1\nscenario: t\nworld: {dt: 0.01, duration: 0.1}\nbodies:\n"
        "  ground: {plane: {}, motion: static}\n"
        f"robots:\n  arm:\n{robot}{extra}"
    )
    return path


def _issues(path: Path) -> list[str]:
    with pytest.raises(ScenarioValidationError) as caught:
        build_program(load_scenario(path))
    return [str(i) for i in caught.value.issues]


def test_kuka_starts_where_its_urdf_kinematics_put_it(tmp_path: Path) -> None:
    """Pose A of kuka_arm.yaml (q2 = 0.5, q4 = -1.0): link 7 at (0.681154, 0, 0.762609), figures from
    yourdfpy's forward kinematics of the same URDF (tests/language/test_robot_examples.py), printed to 1e-6;
    the joints read the start, and the stops move with it (the URDF's +-2.0944 rad on joint 2)."""
    path = _write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n"
                  "    initial: {joints: {lbr_iiwa_joint_2: 0.5, lbr_iiwa_joint_4: -1.0}}\n")  # fmt: skip
    program = build_program(load_scenario(path))
    world = program.world
    hand = world.bodies[world.body_index("arm.lbr_iiwa_link_7")]
    assert hand.pos == pytest.approx((0.681154, 0.0, 0.762609), abs=1e-6)
    assert program.joint_zeros == {"arm.lbr_iiwa_joint_2": 0.5, "arm.lbr_iiwa_joint_4": -1.0}
    j2 = next(j for j in world.joints if j.name == "arm.lbr_iiwa_joint_2")
    model = next(j for j in load_scenario(path).robots["arm"].joints if j.name == "lbr_iiwa_joint_2")
    assert model.lo is not None and model.hi is not None
    assert (model.lo, model.hi) == pytest.approx((-2.0944, 2.0944), abs=1e-4)
    assert (j2.lo, j2.hi) == (model.lo - 0.5, model.hi - 0.5)


def test_every_kuka_link_is_where_yourdfpy_puts_it(tmp_path: Path) -> None:
    """All 7 joints turned: every link's frame (position and rotation) equals yourdfpy's forward kinematics of
    the same URDF, to float64 rounding over 7 composed transforms (1e-12)."""
    import yourdfpy

    from backends.geometry import quat_matrices

    folder = Path(__import__("pybullet_data").getDataPath()) / "kuka_iiwa"
    urdf = yourdfpy.URDF.load(str(folder / "model.urdf"), load_meshes=False)
    cfg = np.array([0.3, -0.5, 0.7, -1.1, 0.4, 0.9, -0.2])
    urdf.update_cfg(cfg)
    joints = ", ".join(f"lbr_iiwa_joint_{k + 1}: {q}" for k, q in enumerate(cfg))
    path = _write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n    initial: {{joints: {{{joints}}}}}\n")
    world = build_program(load_scenario(path)).world
    for body in world.bodies[1:]:
        frame = urdf.get_transform(body.name.split(".")[1], "lbr_iiwa_link_0")
        assert body.pos == pytest.approx(frame[:3, 3], abs=1e-12), body.name
        assert quat_matrices(body.quat) == pytest.approx(frame[:3, :3], abs=1e-12), body.name


def test_link_velocities_are_the_derivative_of_the_placement(tmp_path: Path) -> None:
    """Each link's velocity from the joint rates is d/dt of its forward-kinematics pose: compared with a
    central difference over +-1e-6 s, whose error is O(dt^2 |x'''|) < 1e-9 for rates of order 1 rad/s on a
    1 m arm."""
    path = _write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n")
    desc = load_scenario(path).robots["arm"]
    rates = {f"lbr_iiwa_joint_{k}": (0.3 * k - 1.0, 0.7 - 0.2 * k) for k in range(1, 8)}
    now = link_motions(desc, rates)
    step = 1e-6
    ahead = link_motions(desc, {j: (q + v * step, v) for j, (q, v) in rates.items()})
    behind = link_motions(desc, {j: (q - v * step, v) for j, (q, v) in rates.items()})
    for link in desc.links[1:]:
        x0 = np.asarray(link.pos, dtype=float)
        x = now[link.name].apply(x0)
        numeric = (ahead[link.name].apply(x0) - behind[link.name].apply(x0)) / (2 * step)
        assert now[link.name].velocity(x) == pytest.approx(numeric, abs=1e-8), link.name
        turn = (ahead[link.name].rot - behind[link.name].rot) / (2 * step) @ now[link.name].rot.T  # [omega]x
        omega = np.array([turn[2, 1], turn[0, 2], turn[1, 0]])
        assert now[link.name].omega == pytest.approx(omega, abs=1e-8), link.name


def test_a_start_outside_the_limits_is_refused_at_the_value(tmp_path: Path) -> None:
    path = _write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n"
                  "    initial:\n      joints:\n        lbr_iiwa_joint_2: {pos: 3.5, vel: 0}\n")  # fmt: skip
    command = [sys.executable, "-m", "runner", "validate", str(path)]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 2, done.stderr
    assert f"{path}:12:33: robots.arm.initial.joints.lbr_iiwa_joint_2.pos:" in done.stderr  # at `3.5`
    assert "joint `lbr_iiwa_joint_2` starts at 3.5, outside its limits [-2.0944, 2.0944]" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_start_names_hinges_and_sliders_of_the_model(tmp_path: Path) -> None:
    path = _write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n"
                  "    initial: {joints: {lbr_iiwa_joint_9: 0.1}, keyframe: home}\n")  # fmt: skip
    issues = " ".join(_issues(path))
    assert "unknown joint `lbr_iiwa_joint_9`" in issues
    assert "unknown keyframe (MJCF <key>) `home`" in issues


MJCF = """<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" range="-1.5 1.5"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="1"/>
      <body name="tip" pos="0 0 -0.5">
        <joint name="slide" type="slide" axis="0 0 1" range="-0.1 0.1"/>
        <geom type="sphere" size="0.05" mass="0.5"/>
      </body>
    </body>
    <body name="ball" pos="1 0 1"><freejoint/><geom type="sphere" size="0.1"/></body>
  </worldbody>
  <keyframe>
    <key name="tilted" qpos="0.8 0.05 1 0 1 1 0 0 0" qvel="2 0 0 0 0 0 0 0"/>
    <key name="thrown" qpos="0 0 1 0 1 1 0 0 0" qvel="0 0 1 0 0 0 0 0"/>
    <key name="beyond" qpos="2 0 1 0 1 1 0 0 0"/>
  </keyframe>
</mujoco>
"""


def test_a_keyframe_is_read_and_checked(tmp_path: Path) -> None:
    pytest.importorskip("mujoco", reason="reading MJCF needs MuJoCo's compiler")
    (tmp_path / "p.xml").write_text(MJCF)
    path = _write(tmp_path, "    mjcf: p.xml\n    initial: {keyframe: tilted}\n")
    program = build_program(load_scenario(path))
    assert program.joint_zeros == {"arm.hinge": 0.8, "arm.slide": 0.05}
    assert program.world.models[0].start == (("arm.hinge", 0.8, 2.0), ("arm.slide", 0.05, 0.0))
    tip = program.world.bodies[program.world.body_index("arm.tip")]
    assert tip.pos == pytest.approx((-0.45 * np.sin(0.8), 0.0, 1 - 0.45 * np.cos(0.8)), abs=1e-12)
    assert tip.ang_vel == pytest.approx((0.0, 2.0, 0.0), abs=1e-12)  # the hinge's rate about y
    thrown = _write(tmp_path, "    mjcf: p.xml\n    initial: {keyframe: thrown}\n", name="t.yaml")
    assert "moves the free or ball joint(s) `ball_free`" in " ".join(_issues(thrown))
    beyond = _write(tmp_path, "    mjcf: p.xml\n    initial: {keyframe: beyond}\n", name="b.yaml")
    assert "joint `hinge` starts at 2, outside its limits [-1.5, 1.5]" in " ".join(_issues(beyond))


def test_actions_and_contacts_take_robot_parts(tmp_path: Path) -> None:
    extra = (
        "on:\n  start:\n"
        "    - force: {body: arm.lbr_iiwa_link_7, value: [1, 0, 0]}\n"
        "    - impulse: {body: arm.lbr_iiwa_link_3, value: [0, 1, 0]}\n"
        "    - apply: {body: arm.lbr_iiwa_link_7, force: [0, 0, 5], at: [0, 0, 0.1], frame: body, for: 0.05}\n"
        "    - motor: {joint: arm.lbr_iiwa_joint_1, vel: 0.2, fmax: 50}\n"
        "assertions:\n  - {name: c, contact: [arm.lbr_iiwa_link_7, ground], when: never}\n"
    )
    path = _write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n", extra)
    program = build_program(load_scenario(path))
    joint = next(j for j in program.world.joints if j.name == "arm.lbr_iiwa_joint_1")
    assert joint.motor is not None  # off until the action (an engine building the file needs it now)


def test_a_jointed_link_is_not_reset_nor_a_servo_joint_motored(tmp_path: Path) -> None:
    extra = (
        "on:\n  start:\n    - reset: arm.lbr_iiwa_link_3\n"
        "    - motor: {joint: arm.lbr_iiwa_joint_2, vel: 0.2}\n"
        "    - apply: {body: arm.nothing, force: [0, 0, 1], until: time > 1}\n"
    )
    servo = "{lbr_iiwa_joint_2: {servo: {target: 0, gain: 1, fmax: 1}}}"
    robot = f"    urdf: \"{KUKA}\"\n    fixed: true\n    joints: {servo}\n"
    issues = " ".join(_issues(_write(tmp_path, robot, extra)))
    assert "body `arm.lbr_iiwa_link_3` is held by a joint" in issues
    assert "joint `arm.lbr_iiwa_joint_2` has a servo" in issues
    assert "unknown body `arm.nothing`" in issues


@pytest.mark.parametrize("ends", ["", "for: 1, until: time > 1"])
def test_apply_takes_exactly_one_end(tmp_path: Path, ends: str) -> None:
    tail = ", " + ends if ends else ""
    extra = f"on:\n  start:\n    - apply: {{body: arm.lbr_iiwa_link_7, force: [0, 0, 1]{tail}}}\n"
    issues = " ".join(_issues(_write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n", extra)))
    assert "expected exactly one of `for` (seconds) or `until` (a condition)" in issues


def test_a_start_velocity_is_for_a_free_root(tmp_path: Path) -> None:
    """`initial: {vel, angvel}` moves a free root link (its frame's origin, world frame) and the links it
    carries rigidly; a root welded to the world is refused at the value."""
    spin = "    initial: {vel: [1, 0, 0], angvel: [0, 0, 2]}\n"
    issues = " ".join(_issues(_write(tmp_path, f"    urdf: \"{KUKA}\"\n    fixed: true\n{spin}")))
    assert "a start velocity is for a free root link; robot `arm` is welded to the world (`fixed`)" in issues
    free = "@pybullet_data/kuka_iiwa/model_free_base.urdf"  # its base has a mass
    path = _write(tmp_path, f"    urdf: \"{free}\"\n    pos: [0, 0, 1]\n{spin}", name="free.yaml")
    world = build_program(load_scenario(path)).world
    base, hand = (world.bodies[world.body_index(f"arm.lbr_iiwa_link_{k}")] for k in (0, 7))
    assert base.lin_vel == (1.0, 0.0, 0.0) and base.ang_vel == (0.0, 0.0, 2.0)
    arm = np.subtract(hand.pos, base.pos)  # the hand above the base: v = v0 + omega x r, omega along z
    assert hand.lin_vel == pytest.approx(np.add((1.0, 0.0, 0.0), np.cross((0.0, 0.0, 2.0), arm)), abs=1e-15)
    assert hand.ang_vel == pytest.approx((0.0, 0.0, 2.0), abs=1e-15)
