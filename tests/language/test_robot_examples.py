"""The example robot scenarios (scenarios/robots/): they load and compile, every engine declares what they
need (they run on every engine: tests/backends/test_robot_contract.py, `pytest scenarios/robots`), and the expected
numbers written in their files are re-derived here from the model files with tools we did not write
(yourdfpy's forward kinematics, trimesh's stable poses, the URDF's inertials)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from backends.errors import UnsupportedFeature
from backends.registry import KNOWN_BACKENDS, check_capabilities, get_backend
from backends.types import ROBOT_CAPABILITIES, Capability
from runner.compile.program import build_program
from runner.language.load import load_all
from runner.language.robot_desc import data_root
from tests.paths import ROOT

ROBOTS = sorted((ROOT / "scenarios" / "robots").glob("*.yaml"))
DATA = data_root("@pybullet_data")[0]  # type: ignore[index]
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in)]
#: What an engine is documented not to declare, so that it refuses the examples needing it up front
#: (docs/robots.md): none at present (drake declares convex hulls since issue 32, docs/backends/drake.md).
NOT_DECLARED: dict[str, frozenset[Capability]] = {}


def _assertion(path: Path, name: str) -> dict[str, object]:
    case = load_all(path, None, False)[0]
    found = next(a for a in case.model.assertions if a.name == name)
    return found.model_dump()


def test_the_examples_exist() -> None:
    assert {p.name for p in ROBOTS} == {
        "kuka_arm.yaml",
        "cartpole_pendulum.yaml",
        "duck_drop.yaml",
        "mjcf_box.yaml",
        "pendulum5.yaml",
        "swing_arm.yaml",
        "keyframe_pendulum.yaml",
        "kuka_start.yaml",
        "thruster.yaml",
        "kuka_track.yaml",
        "gripper_push.yaml",
        "actuated_rod.yaml",
        "kuka_loads.yaml",
    }


@pytest.mark.parametrize("path", ROBOTS, ids=[p.stem for p in ROBOTS])
@pytest.mark.parametrize("engine", ENGINES)
def test_every_engine_accepts_them(path: Path, engine: str) -> None:
    if path.stem in ("mjcf_box", "keyframe_pendulum"):
        pytest.importorskip("mujoco", reason="mujoco not installed (MJCF is read by MuJoCo's compiler)")
    try:
        cls = get_backend(engine)
    except Exception as exc:  # noqa: BLE001 - BackendNotInstalled: the engine is not installed here
        pytest.skip(f"{engine} not installed: {exc}")
    for case in load_all(path, None, True):
        world = build_program(case).world
        assert world.required_capabilities() & ROBOT_CAPABILITIES  # a robot: the check below is not vacuous
        lacking = world.required_capabilities() - cls.capabilities
        if lacking and lacking <= NOT_DECLARED.get(engine, frozenset()):  # refused up front, naming it
            with pytest.raises(UnsupportedFeature, match=", ".join(sorted(c.value for c in lacking))):
                check_capabilities(cls, world)
            continue
        check_capabilities(cls, world)  # raises UnsupportedFeature with the capability message otherwise


def test_kuka_targets_match_yourdfpy_forward_kinematics() -> None:
    import yourdfpy

    urdf = yourdfpy.URDF.load(str(DATA / "kuka_iiwa" / "model.urdf"), load_meshes=False)
    path = ROOT / "scenarios" / "robots" / "kuka_arm.yaml"
    for q2, q4, xname, zname in (
        (0.5, -1.0, "pose-a-hand-x", "pose-a-hand-z"),
        (-0.4, 1.2, "pose-b-hand-x", "pose-b-hand-z"),
    ):
        cfg = np.zeros(7)
        cfg[1], cfg[3] = q2, q4
        urdf.update_cfg(cfg)
        hand = urdf.get_transform("lbr_iiwa_link_7", "lbr_iiwa_link_0")[:3, 3]
        assert float(_assertion(path, xname)["near"]) == pytest.approx(hand[0], abs=1e-6)  # type: ignore[arg-type]
        assert float(_assertion(path, zname)["near"]) == pytest.approx(hand[2], abs=1e-6)  # type: ignore[arg-type]
        assert hand[1] == pytest.approx(0.0, abs=1e-9)
    urdf.update_cfg(np.zeros(7))
    assert urdf.get_transform("lbr_iiwa_link_7", "lbr_iiwa_link_0")[2, 3] == pytest.approx(1.261, abs=1e-12)
    start = ROOT / "scenarios" / "robots" / "kuka_start.yaml"  # started at pose A: the same figures
    for axis in ("x", "z"):
        assert _assertion(start, f"hand-starts-at-{axis}")["near"] == _assertion(path, f"pose-a-hand-{axis}")["near"]


def test_cartpole_period_from_the_urdf() -> None:
    import yourdfpy

    urdf = yourdfpy.URDF.load(str(DATA / "cartpole.urdf"), load_meshes=False)
    pole = urdf.link_map["pole"].inertial
    m, d, i_c = pole.mass, pole.origin[2, 3], pole.inertia[1, 1]
    theta0 = math.radians(10)
    t0 = 2 * math.pi * math.sqrt((i_c + m * d * d) / (m * 9.81 * d))
    period = t0 * (1 + theta0**2 / 16 + 11 * theta0**4 / 3072)
    found = _assertion(ROOT / "scenarios" / "robots" / "cartpole_pendulum.yaml", "half-period-extreme")
    assert float(found["near"]) == pytest.approx(2 * theta0, abs=1e-6)  # type: ignore[arg-type]
    assert float(found["at"]) == pytest.approx(period / 2, abs=0.005 / 2)  # type: ignore[arg-type]
    # and the compiled start: the pole hangs 10 degrees off the downward vertical
    world = build_program(load_all(ROOT / "scenarios" / "robots" / "cartpole_pendulum.yaml", None, False)[0]).world
    from backends.geometry import quat_rotate

    pole_z = quat_rotate(next(b for b in world.bodies if b.name == "cartpole.pole").quat, (0.0, 0.0, 1.0))
    assert math.degrees(math.acos(-pole_z[2])) == pytest.approx(10.0, abs=1e-9)


def test_duck_rest_pose_from_trimesh_stable_poses() -> None:
    import trimesh

    from runner.language.hpr import hpr_to_quat
    from runner.language.robot_desc import quat_from_matrix

    mesh = trimesh.load(str(DATA / "duck_vhacd.obj"), force="mesh")
    mesh.apply_scale(0.05)
    transforms, probabilities = trimesh.poses.compute_stable_poses(mesh.convex_hull, center_mass=[0, 0.02, 0])
    best = transforms[int(np.argmax(probabilities))]
    path = ROOT / "scenarios" / "robots" / "duck_drop.yaml"
    assert float(_assertion(path, "rest-height")["near"]) == pytest.approx(best[2, 3], abs=1e-6)  # type: ignore[arg-type]
    robot = load_all(path, None, False)[0].model.robots["duck"]
    q = hpr_to_quat(robot.hpr)  # type: ignore[arg-type]
    expected = quat_from_matrix(best[:3, :3])
    assert abs(abs(float(np.dot(q, expected))) - 1.0) < 1e-9  # the same orientation (q and -q alike)
    assert robot.pos[2] == pytest.approx(best[2, 3] + 0.1, abs=1e-6)


@pytest.mark.slow
def test_kuka_links_never_touch_along_the_commanded_path() -> None:
    """Non-adjacent links' hulls stay apart along the straight joint-space path zero -> pose A -> pose B (the
    servos' paths: each joint's error decays at the same rate, so the path is that straight line), and the
    hand stays above the ground: the arm's only contacts are the excluded adjacent pairs. Hull overlap is a
    linear program (scipy): a point inside both hulls with slack t exists iff t > 0 at the optimum."""
    import itertools

    import trimesh
    import yourdfpy
    from scipy.optimize import linprog

    folder = DATA / "kuka_iiwa"
    urdf = yourdfpy.URDF.load(str(folder / "model.urdf"), load_meshes=False)
    hulls = {
        link.name: trimesh.load(str(folder / link.collisions[0].geometry.mesh.filename), force="mesh").convex_hull
        for link in urdf.robot.links
    }
    adjacent = {tuple(sorted((j.parent, j.child))) for j in urdf.robot.joints}

    def slack(a: trimesh.Trimesh, b: trimesh.Trimesh) -> float:
        normals = np.vstack([a.face_normals, b.face_normals])
        offsets = np.concatenate([np.einsum("ij,ij->i", m.face_normals, m.triangles[:, 0]) for m in (a, b)])
        found = linprog([0, 0, 0, -1], A_ub=np.hstack([normals, np.ones((len(normals), 1))]), b_ub=offsets,
                        bounds=[(None, None)] * 3 + [(None, 1)])  # fmt: skip
        return float(found.x[3])

    waypoints = [(0.0, 0.0), (0.5, -1.0), (-0.4, 1.2)]
    for (a2, a4), (b2, b4) in itertools.pairwise(waypoints):
        for s in np.linspace(0.0, 1.0, 6):
            cfg = np.zeros(7)
            cfg[1], cfg[3] = a2 + s * (b2 - a2), a4 + s * (b4 - a4)
            urdf.update_cfg(cfg)
            placed = {n: h.copy().apply_transform(urdf.get_transform(n, "lbr_iiwa_link_0")) for n, h in hulls.items()}
            for x, y in itertools.combinations(sorted(placed), 2):
                if (x, y) not in adjacent:
                    assert slack(placed[x], placed[y]) < 0, (x, y, cfg)
            assert min(placed[n].vertices[:, 2].min() for n in placed if n >= "lbr_iiwa_link_2") > 0.05


def test_kuka_loads_are_the_urdf_masses_above_each_joint() -> None:
    """kuka_loads.yaml's params: the masses of links 1..7, 4..7 and 7 as the URDF's <inertial> gives them."""
    import yourdfpy

    urdf = yourdfpy.URDF.load(str(DATA / "kuka_iiwa" / "model.urdf"), load_meshes=False)
    mass = {name: link.inertial.mass for name, link in urdf.link_map.items() if link.inertial is not None}
    params = load_all(ROOT / "scenarios" / "robots" / "kuka_loads.yaml", None, False)[0].model.params
    for param, first in (("m1", 1), ("m4", 4), ("m7", 7)):
        held = sum(mass[f"lbr_iiwa_link_{k}"] for k in range(first, 8))
        assert params[param] == pytest.approx(held, abs=1e-12)
