"""Joint reactions on PyBullet: force/torque sensors on the joints a scenario reads, reported as the wrench
each joint applies to its first body (capability ``joint:reaction``)."""

from __future__ import annotations

import numpy as np
import pybullet as p

from ..types import CompiledWorld, JointKind
from ._build import Layout


class ReactionSensors:
    """A force/torque sensor on each joint of ``world.reaction_joints``, reporting in world axes about the
    joint's pivot (the child link's frame origin: jointFeedbackMode world space | joint frame); per joint
    (multibody, link, +1 when the link is the joint's first body else -1, the first body's multibody and
    link, the joint's axis in the link frame for a motor's torque (empty without one), whether it is a
    slider). The sensor leaves out what a joint's motor applies along its axis: added from its applied
    torque (getJointState's fourth value, the coordinate's force). Only when the scenario reads a
    reaction: the mode is the client's, the sensors cost a pass."""

    def __init__(self, c: int, world: CompiledWorld, layout: Layout) -> None:
        self._c = c
        self.watched: list[tuple[int, int, float, int, int, tuple[float, ...], bool]] = []
        names = world.reaction_joints
        if not names:
            return
        p.setPhysicsEngineParameter(
            jointFeedbackMode=p.JOINT_FEEDBACK_IN_WORLD_SPACE | p.JOINT_FEEDBACK_IN_JOINT_FRAME, physicsClientId=c
        )
        index = {j.name: k for k, j in enumerate(world.joints)}
        for name in names:
            k = index[name]
            handle = layout.joints[k]
            first = world.body_index(world.joints[k].body)
            p.enableJointForceTorqueSensor(handle.uid, handle.link, True, physicsClientId=c)
            axis = tuple(p.getJointInfo(handle.uid, handle.link, physicsClientId=c)[13]) if handle.dofs == 1 else ()
            slider = world.joints[k].kind is JointKind.SLIDER
            self.watched.append(
                (handle.uid, handle.link, handle.sign, layout.uid[first], layout.link[first], axis, slider)
            )

    def __bool__(self) -> bool:
        return bool(self.watched)

    def __len__(self) -> int:
        return len(self.watched)

    def now(self) -> list[float]:
        """The watched joints' wrenches on their first bodies after this engine step: force, and torque about
        the first body's centre of mass (moved from the pivot: tau_c = tau_p + (pivot - c) x F)."""
        c, out = self._c, []  # type: tuple[int, list[float]]
        for uid, link, sign, body_uid, body_link, axis, slider in self.watched:
            state = p.getJointState(uid, link, physicsClientId=c)
            frame = p.getLinkState(uid, link, physicsClientId=c)
            pivot, wrench = np.asarray(frame[4]), np.array(state[2])
            if axis:  # the motor's force or torque along the axis (the link frame's orientation: frame[5])
                turn = np.asarray(p.getMatrixFromQuaternion(frame[5], physicsClientId=c)).reshape(3, 3)
                along = state[3] * (turn @ np.asarray(axis))
                wrench[0:3] += along if slider else 0.0
                wrench[3:6] += 0.0 if slider else along
            if body_link < 0:
                com = np.asarray(p.getBasePositionAndOrientation(body_uid, physicsClientId=c)[0])
            else:
                com = np.asarray(p.getLinkState(body_uid, body_link, physicsClientId=c)[0])
            force, torque = sign * np.asarray(wrench[:3]), sign * np.asarray(wrench[3:])
            out.extend((*force, *(torque + np.cross(pivot - com, force))))
        return out
