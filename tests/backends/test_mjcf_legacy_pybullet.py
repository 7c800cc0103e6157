"""MJCF's legacy dialect, upgraded (runner.language.mjcf_legacy), means what pybullet's own `loadMJCF` reads in
the same unmodified file: every body's world frame at the zero configuration (the file's pose) and its mass.

The 8 files of pybullet_data that MuJoCo 4 refuses (global coordinates, a `fixed` joint, an `<inertial>`
without `pos`, a missing material, `<option collision>`, tendons and motors naming absent joints, a plane
without a grid size) load through the upgrade; pybullet reads them as they are. Its MJCF importer makes a link
per body (named as the body; each joint a massless link before it) whose URDF link frame
(`getLinkState(...)[4:6]`) is the body's frame, and a multibody per top-level body or geom.

Bound: pybullet's MJCF parser reads every number as a float (`parseVector3` collects `btArray<float>`),
a relative rounding of 2**-24 = 6e-8 on each; MuJoCo reads doubles. A body's world frame composes at most 6
offsets (humanoid: torso, lwaist, pelvis, thigh, shin, foot) of at most 0.5 m, each also turned by float
orientations (6e-8 rad each) on lever arms of at most 2 m: the frames agree within 6 * 0.5 * 6e-8 +
6 * 6e-8 * 2 = 9e-7 m, taken as ``POS_TOL`` = 1e-6 m, and ``ANGLE_TOL`` = 1e-6 rad. Masses are 1000 x volume on
both (pybullet ignores `mass=`, none of these files gives one) from float sizes: within 3 x 6e-8 relative,
``MASS_TOL`` = 1e-6. A misread construct shows at the files' printed precision (1e-3) or more.

Two readings differ by pybullet's loader, not by the upgrade, and the test says how:
- a top-level body without a joint (humanoid_symmetric's torso) becomes pybullet's base, and pybullet puts
  the base's centre of mass (its `localInertialFramePosition`) where the file puts the body's frame: the whole
  model is displaced by that offset, which the test removes before comparing;
- half_cheetah's masses: pybullet ignores `<compiler settotalmass="14">` and `inertiafromgeom="true"` (it takes
  the feet's `<inertial mass="10">`, which MuJoCo's compiler overrides with the geoms'): MuJoCo's bodies
  without `<inertial>` weigh pybullet's times one factor, and the model 14 kg.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from runner.language.mjcf import load_mjcf

p = pytest.importorskip("pybullet", reason="pybullet is a base dependency")
pybullet_data = pytest.importorskip("pybullet_data")
pytest.importorskip("mujoco", reason="reading MJCF needs MuJoCo's compiler (the `mujoco` extra)")

DATA = Path(pybullet_data.getDataPath()) / "mjcf"
POS_TOL, ANGLE_TOL, MASS_TOL = 1e-6, 1e-6, 1e-6  # m, rad, relative (module docstring)
LEGACY = ("hopper", "walker2d", "half_cheetah", "humanoid_fixed", "humanoid_symmetric", "swimmer", "ground",
          "ground_plane")  # fmt: skip


def _matrix(xyzw: tuple[float, ...]) -> np.ndarray:
    return np.asarray(p.getMatrixFromQuaternion(xyzw), dtype=float).reshape(3, 3)


Frames = dict[str, tuple[np.ndarray, np.ndarray, float]]
Axes = dict[str, tuple[np.ndarray, np.ndarray]]


def _pybullet(file: Path) -> tuple[Frames, Axes, list[np.ndarray]]:
    """pybullet's `loadMJCF`: each named link's world frame (position, rotation) and mass, a jointless
    top-level body's displacement removed (module docstring); each moving joint's world frame (the massless
    link it makes, at the joint's `pos`) and its axis in that frame; and the world positions of the planes of
    the multibodies made from top-level geoms."""
    c = p.connect(p.DIRECT)
    try:
        p.setPhysicsEngineParameter(enableFileCaching=0, physicsClientId=c)
        links: Frames = {}
        joints: Axes = {}
        planes: list[np.ndarray] = []
        for uid in p.loadMJCF(str(file), physicsClientId=c):
            base = p.getBodyInfo(uid, physicsClientId=c)[0].decode()
            com, com_quat = p.getBasePositionAndOrientation(uid, physicsClientId=c)
            info = p.getDynamicsInfo(uid, -1, physicsClientId=c)
            frame, frame_quat = p.multiplyTransforms(com, com_quat, *p.invertTransform(info[3], info[4]))
            # a body as the base (mass): its centre of mass was put at the body's place, so all moved by this
            shift = np.asarray(com) - np.asarray(frame) if info[0] > 0 else np.zeros(3)
            links[base] = (np.asarray(frame) + shift, _matrix(frame_quat), float(info[0]))
            top_geom = info[0] == 0 and not p.getNumJoints(uid, physicsClientId=c)  # (on a body: a segfault)
            for shape in p.getCollisionShapeData(uid, -1, physicsClientId=c) if top_geom else ():
                if shape[2] == p.GEOM_PLANE:
                    planes.append(np.asarray(p.multiplyTransforms(com, com_quat, shape[5], shape[6])[0]))
            for j in range(p.getNumJoints(uid, physicsClientId=c)):
                info = p.getJointInfo(uid, j, physicsClientId=c)
                state = p.getLinkState(uid, j, computeForwardKinematics=1, physicsClientId=c)
                mass = float(p.getDynamicsInfo(uid, j, physicsClientId=c)[0])
                links[info[12].decode()] = (np.asarray(state[4]) + shift, _matrix(state[5]), mass)
                if info[2] != p.JOINT_FIXED:
                    axis = _matrix(state[5]) @ np.asarray(info[13])
                    joints[info[1].decode()] = (np.asarray(state[4]) + shift, axis / np.linalg.norm(axis))
        return links, joints, planes
    finally:
        p.disconnect(c)


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(a.T @ b) - 1.0) / 2.0, -1.0, 1.0)))


@pytest.mark.parametrize("model", LEGACY)
def test_the_upgraded_file_places_every_body_as_loadmjcf(model: str) -> None:
    from runner.language.mjcf_global import _quat_matrix  # the same rotation MuJoCo's quaternion means

    desc = load_mjcf(DATA / f"{model}.xml")
    assert any(note.startswith("legacy MJCF") for note in desc.notes)  # upgraded, and said so
    links, joints, planes = _pybullet(DATA / f"{model}.xml")
    bodies = [link for link in desc.links if link.name != "worldbody"]
    assert {link.name for link in bodies} <= set(links), (sorted(links), [b.name for b in bodies])
    for link in bodies:
        pos, rot, _ = links[link.name]
        assert np.linalg.norm(pos - np.asarray(link.pos)) <= POS_TOL, (link.name, pos, link.pos)
        assert _angle(rot, _quat_matrix(np.asarray(link.quat))) <= ANGLE_TOL, link.name
    moving = [j for j in desc.joints if j.kind in ("hinge", "slider")]  # where and about what each turns
    assert {j.name for j in moving} == set(joints)
    for joint in moving:
        anchor, axis = joints[joint.name]
        assert np.linalg.norm(anchor - np.asarray(joint.anchor)) <= POS_TOL, (joint.name, anchor, joint.anchor)
        assert np.linalg.norm(axis - np.asarray(joint.axis)) <= ANGLE_TOL, (joint.name, axis, joint.axis)
    world_planes = [np.asarray(s.pos) for s in desc.links[0].shapes if s.shape.kind.name == "PLANE"]
    if model in ("ground", "ground_plane"):  # the files hold only their floor: pybullet's one multibody
        assert len(world_planes) == len(planes) == 1 and np.linalg.norm(world_planes[0] - planes[0]) <= POS_TOL


@pytest.mark.parametrize("model", [m for m in LEGACY if m not in ("half_cheetah", "ground", "ground_plane")])
def test_the_upgraded_file_weighs_every_body_as_loadmjcf(model: str) -> None:
    desc = load_mjcf(DATA / f"{model}.xml")
    links, _, _ = _pybullet(DATA / f"{model}.xml")
    for link in desc.links[1:]:
        assert abs(link.mass - links[link.name][2]) <= MASS_TOL * links[link.name][2], link.name


def test_half_cheetah_weighs_what_settotalmass_makes_of_loadmjcfs_masses() -> None:
    """pybullet ignores `settotalmass` and `inertiafromgeom="true"` (module docstring): MuJoCo's masses of the
    bodies without `<inertial>` are pybullet's times one factor, and the model weighs 14 kg."""
    desc = load_mjcf(DATA / "half_cheetah.xml")
    links, _, _ = _pybullet(DATA / "half_cheetah.xml")
    assert abs(sum(link.mass for link in desc.links[1:]) - 14.0) <= 14.0 * MASS_TOL
    ratios = [link.mass / links[link.name][2] for link in desc.links[1:] if link.name not in ("bfoot", "ffoot")]
    assert len(ratios) == 5 and max(ratios) - min(ratios) <= 2 * MASS_TOL * max(ratios), ratios
    assert [links[f][2] for f in ("bfoot", "ffoot")] == [10.0, 10.0]  # pybullet's `<inertial mass="10">`
