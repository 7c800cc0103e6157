"""PyBullet's inertial-to-body frame conversion (backends/pybullet/_frames.py). For bases it runs on plain floats
for a few offset bodies and on whole columns for more; robot links are converted on getLinkStates' tuples as
they are read. All are the same operations in the same order, so they must give the same numbers to the bit
(traces do not change with the number of links or the read's path), signed zeros included. Bullet's own link
frame (getLinkState's fields 4 and 5) would be cheaper but is single precision: its deviation is bounded by
float32 rounding, far above the double-precision conversion's."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from backends.registry import is_installed
from backends.types import CompiledWorld
from runner.compile.program import build_program
from runner.language.load import load_scenario
from tests.paths import ROOT

pytestmark = pytest.mark.skipif(not is_installed("pybullet"), reason="engine not installed: pybullet")


def test_the_column_conversion_is_the_per_body_one_to_the_bit(monkeypatch: pytest.MonkeyPatch) -> None:
    from backends.pybullet import _frames

    world = build_program(load_scenario(ROOT / "bench" / "scenarios" / "quadruped.yaml")).world
    frames = _frames.InertialFrames(world)
    assert len(frames.offsets) > _frames.PER_BODY_UP_TO  # the quadruped's legs take the column path
    rng = np.random.default_rng(29)
    rows = rng.normal(size=(len(world.bodies), 13))
    rows[:, 3:7] /= np.linalg.norm(rows[:, 3:7], axis=1, keepdims=True)  # unit quaternions (x y z w)
    first = int(next(iter(frames.offsets)))
    rows[first, :] = -0.0  # a state of signed zeros keeps its signs on both paths
    per_body, columns = rows.copy(), rows.copy()
    monkeypatch.setattr(_frames, "PER_BODY_UP_TO", len(frames.offsets))
    frames.to_body(per_body)
    monkeypatch.setattr(_frames, "PER_BODY_UP_TO", 0)
    frames.to_body(columns)
    assert not np.array_equal(per_body, rows)  # the conversion did move the offset bodies
    assert per_body.tobytes() == columns.tobytes()


def _robot(path: Path) -> tuple[CompiledWorld, Any, list[tuple[int, list[int], list[int], Any, Any]]]:
    """The adapter built on a robot scenario, and its multibodies with links (uid, links, bodies, their rows,
    the conversion)."""
    from backends.pybullet import PyBulletBackend

    world = build_program(load_scenario(path)).world
    adapter = PyBulletBackend(world)
    return world, adapter, adapter._link_reads


def _r2d2(tmp_path: Path) -> Path:
    """pybullet_data's r2d2: a floating base, and links with a COM offset (the legs) beside links without
    (its inertias are isotropic, so no principal axes are turned, though its URDF turns the legs' inertials)."""
    path = tmp_path / "r2d2.yaml"
    path.write_text(
        "schema_version: 1\nscenario: r2d2\nworld: {dt: 0.01, duration: 1}\n"
        "bodies:\n  ground: {plane: {}, motion: static}\n"
        "robots:\n  r: {urdf: '@pybullet_data/r2d2.urdf', pos: [0, 0, 0.6]}\n"
    )
    return path


def _poses(adapter: Any, rng: np.random.Generator, count: int) -> Iterator[None]:
    """The start pose (joint angles 0: quaternions with exact zeros), then ``count`` random joint positions
    and rates (and a random base twist where the base floats), each read after one engine step."""
    import pybullet as p

    c = adapter._c
    yield
    for _ in range(count):
        for uid, links, *_ in adapter._link_reads:
            for link in links:
                if p.getJointInfo(uid, link, physicsClientId=c)[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
                    q, qd = rng.uniform(-2.5, 2.5), rng.uniform(-3.0, 3.0)
                    p.resetJointState(uid, link, q, qd, physicsClientId=c)
            p.resetBaseVelocity(uid, rng.normal(size=3).tolist(), rng.normal(size=3).tolist(), physicsClientId=c)
        adapter.step()
        yield


@pytest.mark.parametrize("robot", ["kuka_arm", "pendulum5", "quadruped", "r2d2"])
def test_links_read_as_body_frames_are_the_conversion_to_the_bit(robot: str, tmp_path: Path) -> None:
    """The links' body frames read on getLinkStates' tuples (``LinkFrames``) against the rows as getLinkStates
    gives them converted by ``_inertial_to_body`` (the conversion bases use): equal bytes at the start pose
    and at random poses and rates, on the KUKA arm (offset COMs, principal axes the links' own), pendulum5
    (URDF) and the bench's MJCF quadruped (turned principal axes), and r2d2 (links with and without an offset
    in one multibody); and the adapter's whole read (unturned static bases read once) is every body's
    fresh read."""
    import pybullet as p

    from backends.geometry import quat_conj
    from backends.pybullet import _frames
    from backends.pybullet._reads import base_rows, link_rows

    robots = ROOT / "scenarios" / "robots"
    path = {"kuka_arm": robots / "kuka_arm.yaml", "pendulum5": robots / "pendulum5.yaml",
            "quadruped": ROOT / "bench" / "scenarios" / "quadruped.yaml", "r2d2": _r2d2(tmp_path)}[robot]  # fmt: skip
    world, adapter, groups = _robot(path)
    try:
        c, converted, zeros, unconverted = adapter._c, 0, 0, 0
        turned = any(tuple(world.bodies[b].inertia_quat) != (1.0, 0.0, 0.0, 0.0) for g in groups for b in g[2])
        assert turned == (robot in ("pendulum5", "quadruped"))  # both branches of the quaternion product
        bases = [i for i in range(len(world.bodies)) if adapter._layout.link[i] < 0]
        for _ in _poses(adapter, np.random.default_rng(29), 12):
            every = np.empty((len(world.bodies), 13))  # every body read afresh: the bases converted as by the adapter
            every[bases] = base_rows(c, [adapter._layout.uid[i] for i in bases])
            adapter._frames.to_body(every)
            for uid, links, bodies, _, frames in groups:
                assert frames is not None  # every one of these robots has offset links
                raw = link_rows(c, uid, links, None)  # the inertial frames, as read
                zeros += int(np.count_nonzero(raw[:, 3:7] == 0.0))
                expected = raw.copy()
                for k, b in enumerate(bodies):
                    spec = world.bodies[b]
                    if frames.offsets[k] is None:
                        unconverted += 1
                        continue
                    conj = (*spec.com, *quat_conj(spec.inertia_quat))
                    expected[k] = _frames._inertial_to_body(*raw[k].tolist(), *map(float, conj))
                    converted += 1
                states = p.getLinkStates(uid, links, computeLinkVelocity=1, computeForwardKinematics=1,
                                         physicsClientId=c)  # fmt: skip
                got = frames.rows(states)
                assert got.tobytes() == expected.tobytes()
                every[bodies] = expected
            # what the adapter reports, its unturned static bases read once at the start
            assert adapter._fresh_rows().tobytes() == every.tobytes()
        assert converted > 0
        assert (unconverted > 0) == (robot == "r2d2")
        if robot == "kuka_arm":
            assert zeros > 0  # the start pose's exact zeros: the product is taken for their signs
    finally:
        adapter.close()


@pytest.mark.parametrize("robot", ["kuka_arm", "pendulum5"])
def test_bullets_link_frame_fields_are_single_precision(robot: str) -> None:
    """getLinkState's worldLinkFramePosition/Orientation (fields 4, 5) are computed by the C API's b3GetLinkState
    in b3Scalar, single precision in pybullet's build: every value is a float32, and they differ from the
    double-precision conversion by float32 rounding, up to the sign of the quaternion. Bound: the C API rounds
    the COM pose and the inertial offset to float32 (half an ulp each, 2^-24 relative), inverts the offset
    (3 products and 2 sums per component) and composes (3 products, 3 sums), then reads the quaternion off the
    rotation matrix (a square root, a division, 3 sums): at most ~16 roundings of 2^-24 each on quantities of
    size |p_com| + |com| (position) or 1 (quaternion), so 16 * 2^-24 * that. If this fails because they are
    double, reading them would be the cheaper exact route (backends/pybullet/_frames.py)."""
    import pybullet as p

    world, adapter, groups = _robot(ROOT / "scenarios" / "robots" / f"{robot}.yaml")
    try:
        c, rng, worst = adapter._c, np.random.default_rng(5), 0.0
        for _ in _poses(adapter, rng, 5):
            for uid, links, bodies, _, frames in groups:
                assert frames is not None
                ours = adapter._fresh_rows()[bodies]
                for k, state in enumerate(p.getLinkStates(uid, links, computeForwardKinematics=1, physicsClientId=c)):
                    pos, quat = np.array(state[4]), np.array(state[5])
                    assert all(float(np.float32(v)) == v for v in (*pos, *quat))  # single precision
                    assert not all(float(np.float32(v)) == v for v in state[0])  # the COM frame is double
                    size = np.linalg.norm(state[0]) + np.linalg.norm(world.bodies[bodies[k]].com)
                    bound = 16 * 2.0**-24
                    assert np.abs(pos - ours[k, 0:3]).max() <= bound * size
                    q = ours[k, 3:7]
                    assert min(np.abs(quat - q).max(), np.abs(quat + q).max()) <= bound
                    worst = max(worst, float(np.abs(pos - ours[k, 0:3]).max()))
        assert worst > 2.0**-52  # they are not the double-precision frames
    finally:
        adapter.close()


def test_the_link_conversion_keeps_the_signs_of_exact_zeros() -> None:
    """``_links_to_body`` leaves the quaternion product out for unturned principal axes, where it returns q but
    may change the sign of an exact zero (x = -0.0 with y, z, w > 0 gives +0.0): the same bytes as
    ``_inertial_to_body`` on synthetic states whose components are exact zeros of either sign, in every place."""
    from backends.geometry import quat_conj
    from backends.pybullet import _frames

    rng = np.random.default_rng(7)
    rows = rng.normal(size=(4000, 13))
    rows[:, 3:7] /= np.linalg.norm(rows[:, 3:7], axis=1, keepdims=True)
    zeros = rng.random(size=rows.shape) < 0.3
    rows[zeros] = np.where(rng.random(size=int(zeros.sum())) < 0.5, -0.0, 0.0)
    states = [(r[0:3], r[3:7], (), (), (), (), r[7:10], r[10:13]) for r in rows.tolist()]
    for com, inertia_quat in (((0.0, -0.03, 0.12), (1.0, 0.0, 0.0, 0.0)), ((0.01, 0.005, -0.15), (0.6, 0.0, 0.8, 0.0))):
        offset = _frames._link_offset(com, inertia_quat)
        got = _frames._links_to_body(states, [offset] * len(states))
        conj = (*com, *quat_conj(inertia_quat))
        expected = [v for r in rows.tolist() for v in _frames._inertial_to_body(*r, *conj)]
        assert np.array(got).tobytes() == np.array(expected).tobytes()


def test_a_turned_static_base_is_read_every_step() -> None:
    """Bullet moves a turned static base's quaternion by an ulp and back every step (its quaternion-matrix round
    trip), so the adapter reads it afresh, and reads only unturned static bases once: on the friction
    conformance's 20-degree incline (a turned static ground) the adapter's rows are the fresh reads' bytes at
    every step, while the ground's own read does change between steps."""
    from backends.pybullet import PyBulletBackend
    from backends.pybullet._reads import base_rows

    world = build_program(load_scenario(ROOT / "scenarios" / "conformance" / "08_friction.yaml", "incline-stays")).world
    adapter = PyBulletBackend(world)
    try:
        c, uids = adapter._c, adapter._layout.uid
        assert adapter._layout.link == [-1] * len(world.bodies)  # bases only: the ground and the box
        ground = [b.name for b in world.bodies].index("ground")
        reads = []
        for _ in range(4):
            every = base_rows(c, uids)
            adapter._frames.to_body(every)
            assert adapter._fresh_rows().tobytes() == every.tobytes()
            reads.append(every[ground].tobytes())
            adapter.step()
        assert len(set(reads)) > 1  # the engine's own read of the static ground changed
    finally:
        adapter.close()
