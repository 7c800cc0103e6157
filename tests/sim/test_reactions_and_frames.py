"""The runner's side of joint reactions and named frames (runner.sim.reactions, runner.sim.frames), judged
against an independent computation with scipy's Rotation: the torque moved from the centre of mass to the
anchor carried by a turned, moving body, the same wrench in the body's axes, and a frame's pose and velocity.
float64 sums of a few terms of size <= 10: 1e-12."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from backends.types import BodySpec, BodyStates, CompiledWorld, JointKind, JointSpec, Motion, Shape, ShapeKind
from runner.sim.frames import frame_getter
from runner.sim.reactions import reaction_getter

START_Q = (0.9238795325112867, 0.0, 0.0, 0.3826834323650898)  # 45 degrees about z


def _rot(q: np.ndarray | tuple[float, ...]) -> np.ndarray:
    return Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_matrix()


def test_the_torque_is_moved_to_the_anchor_the_body_carries_and_turned_into_its_axes() -> None:
    body = BodySpec("link", Motion.DYNAMIC, Shape(ShapeKind.BOX, (0.1, 0.1, 0.1)), 2.0, (0.1, 0.1, 0.1),
                    (1.0, 2.0, 3.0), START_Q, com=(0.2, -0.1, 0.05))  # fmt: skip
    joint = JointSpec("j", JointKind.HINGE, "link", None, axis=(0.0, 0.0, 1.0), anchor=(1.0, 2.5, 3.0))
    world = CompiledWorld("t", (0.0, 0.0, -9.81), 0.01, 1, 1.0, (body,), (joint,), reaction_joints=("j",))
    rng = np.random.default_rng(3)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    pos = rng.normal(size=3)
    states = BodyStates.from_rows(np.hstack([pos, q, rng.normal(size=6)])[None, :])
    wrench = rng.normal(size=(1, 6))
    # independent: the anchor's place in the body at the start, carried to now; the COM now
    anchor_b = _rot(START_Q).T @ (np.array(joint.anchor) - np.array(body.pos))
    r = _rot(q)
    anchor, com = pos + r @ anchor_b, pos + r @ np.array(body.com)
    force, torque_anchor = wrench[0, :3], wrench[0, 3:] + np.cross(com - anchor, wrench[0, :3])
    read = lambda: (states, wrench)  # noqa: E731
    for k, c in enumerate("xyz"):
        assert reaction_getter(world, "j", "force", c, read)() == pytest.approx(force[k], abs=1e-12)
        assert reaction_getter(world, "j", "torque", c, read)() == pytest.approx(torque_anchor[k], abs=1e-12)
        assert reaction_getter(world, "j", "force_body", c, read)() == pytest.approx((r.T @ force)[k], abs=1e-12)
        assert reaction_getter(world, "j", "torque_body", c, read)() == pytest.approx((r.T @ torque_anchor)[k],
                                                                                      abs=1e-12)  # fmt: skip


def test_a_frame_reads_its_pose_velocity_and_spin_from_its_body() -> None:
    rng = np.random.default_rng(4)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    row = np.hstack([rng.normal(size=3), q, rng.normal(size=6)])
    states = BodyStates.from_rows(row[None, :])
    local, local_q = (0.1, -0.2, 0.3), (0.7071067811865476, 0.0, 0.7071067811865476, 0.0)
    r = _rot(q)
    want = {
        "pos": row[0:3] + r @ np.array(local),
        "vel": row[7:10] + np.cross(row[10:13], r @ np.array(local)),
        "angvel": row[10:13],
    }
    for field, value in want.items():
        for k, c in enumerate("xyz"):
            got = frame_getter(0, local, local_q, field, c, lambda: states)()
            assert got == pytest.approx(value[k], abs=1e-12)
    turned = Rotation.from_matrix(r @ _rot(local_q)).as_quat()  # x y z w
    quat = [frame_getter(0, local, local_q, "quat", c, lambda: states)() for c in "wxyz"]
    sign = 1.0 if quat[0] * turned[3] >= 0 else -1.0
    assert np.allclose(quat, sign * np.array([turned[3], *turned[:3]]), atol=1e-12)
