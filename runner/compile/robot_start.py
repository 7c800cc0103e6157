"""A robot's start state (`initial:`): its links placed and moving by forward kinematics of the joints' start.

A model description holds every link at the zero configuration (runner.language.robot_desc). A joint
moves its child (and the child's subtree) relative to its parent: a hinge by a rotation of q about its
axis through its anchor, a slider by a translation q along its axis, both fixed in the parent and written
in the model frame at the zero configuration. So each link's displacement from its zero pose composes down
the tree, D_child = D_parent ∘ M_joint(q), and its velocity is the parent's plus the joint's own: a hinge
adds qd·a to ω and qd·(a × (x − anchor)) to a point x's velocity, a slider qd·a (a, anchor displaced with
the parent). Engines then build the robot at that pose with those velocities as any jointed bodies, and
read each joint from its start (backends/types.py); the runner adds the start position back to the reading
(runner.compile.world.joint_zeros), so a joint reads from the model's zero.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from backends.geometry import IDENTITY, quat_conj, quat_from_axis_angle, quat_mul, quat_rotate
from backends.types import Quat
from runner.language.hpr import hpr_to_quat
from runner.language.model_robots import Robot
from runner.language.robot_desc import ModelDesc


def start_values(robot: Robot, desc: ModelDesc, as_file: bool = False) -> dict[str, tuple[float, float]]:
    """Joint -> (position from the model's zero, rate): the model's own start (a joint whose zero is outside its
    range starts at its nearest end: ``ModelDesc.start``; not ``as_file``, with `world.options: model`, where
    the file starts as MuJoCo starts it), the keyframe's, then the scenario's own."""
    out: dict[str, tuple[float, float]] = {} if as_file else {j: (q, 0.0) for j, q in desc.start}
    start = robot.initial
    if start is None:
        return out
    if start.keyframe is not None:
        key = desc.keyframe(start.keyframe)
        if key is not None:  # refused when loaded otherwise (runner.language.refs)
            out.update({j: (q, v) for j, q, v in key.values if q != 0.0 or v != 0.0})
    out.update(start.values())
    return out


@dataclass(frozen=True)
class LinkMotion:
    """A link's displacement from its zero pose (x -> rot x + shift, model frame) and its velocity as a
    twist (omega, and the velocity of the point at the model's origin)."""

    rot: np.ndarray
    quat: Quat  # the same rotation
    shift: np.ndarray
    omega: np.ndarray
    v_origin: np.ndarray

    def apply(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(self.rot @ x + self.shift, dtype=float)

    def velocity(self, x: np.ndarray) -> np.ndarray:
        """The velocity of the link's point now at ``x`` (model frame)."""
        return np.asarray(self.v_origin + np.cross(self.omega, x), dtype=float)


_REST = LinkMotion(np.eye(3), IDENTITY, np.zeros(3), np.zeros(3), np.zeros(3))


def root_motion(robot: Robot, desc: ModelDesc) -> LinkMotion | None:
    """A free root's start velocity (`initial: {vel, angvel}`, world frame, of its link frame's origin) as a
    twist in the model frame; None when it starts at rest."""
    if robot.initial is None or not robot.initial.moving_root:
        return None
    turn = quat_conj(hpr_to_quat(robot.hpr)) if robot.hpr is not None else IDENTITY
    omega = np.asarray(quat_rotate(turn, robot.initial.angvel), dtype=float)
    v = np.asarray(quat_rotate(turn, robot.initial.vel), dtype=float)
    at = np.asarray(desc.link(desc.root).pos, dtype=float)
    return LinkMotion(np.eye(3), IDENTITY, np.zeros(3), omega, v - np.cross(omega, at))


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.asarray(np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k), dtype=float)


def link_motions(
    desc: ModelDesc, values: Mapping[str, tuple[float, float]], root: LinkMotion | None = None
) -> dict[str, LinkMotion]:
    """Every link's displacement and velocity for the joints' start ``values``, the root link moving as
    ``root`` (default: at rest)."""
    return _walk(desc, values, root)[0]


def joint_motions(
    desc: ModelDesc, values: Mapping[str, tuple[float, float]], root: LinkMotion | None = None
) -> dict[str, tuple[LinkMotion, LinkMotion]]:
    """Per joint, the motion of the frame that carries it and of the frame it moves (its child, or for one of
    several joints of an MJCF body, the body's frame as the joints up to it leave it)."""
    return _walk(desc, values, root)[1]


def _walk(
    desc: ModelDesc, values: Mapping[str, tuple[float, float]], root: LinkMotion | None
) -> tuple[dict[str, LinkMotion], dict[str, tuple[LinkMotion, LinkMotion]]]:
    """The description lists a parent's joint before its children's (both loaders walk from the root), and
    the joints of one MJCF body in order: each turns or slides about its axis as the ones before left the
    body (MuJoCo's kinematics), so a joint whose child already moved is carried by that motion."""
    out: dict[str, LinkMotion] = {} if root is None else {desc.root: root}
    joints: dict[str, tuple[LinkMotion, LinkMotion]] = {}
    for joint in desc.joints:
        parent = out.get(joint.child) or out.get(joint.parent, _REST)
        q, qd = values.get(joint.name, (0.0, 0.0))
        axis = parent.rot @ np.asarray(joint.axis, dtype=float)
        anchor0 = np.asarray(joint.anchor, dtype=float)
        if joint.kind == "hinge":
            turn = _rotation(np.asarray(joint.axis, dtype=float), q)
            rot, shift = parent.rot @ turn, parent.apply(anchor0 - turn @ anchor0)
            quat = quat_mul(parent.quat, quat_from_axis_angle(joint.axis, q))
            anchor = parent.apply(anchor0)
            omega, v_origin = parent.omega + qd * axis, parent.v_origin - qd * np.cross(axis, anchor)
        elif joint.kind == "slider":
            rot, quat, shift = parent.rot, parent.quat, parent.shift + q * axis
            omega, v_origin = parent.omega, parent.v_origin + qd * axis
        else:  # fixed, ball, free: no start of their own
            rot, quat, shift, omega, v_origin = parent.rot, parent.quat, parent.shift, parent.omega, parent.v_origin
        out[joint.child] = LinkMotion(rot, quat, shift, omega, v_origin)
        joints[joint.name] = (parent, out[joint.child])
    return out, joints
