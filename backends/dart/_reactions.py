"""Joint reactions (``joint:reaction``): DART's child body force, turned to the wrench on the joint's first body."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..types import CompiledWorld
from ._build import BodyHandle, JointHandle


class Reactions:
    """The joints of ``world.reaction_joints``, read after each engine step."""

    def __init__(self, world: CompiledWorld, bodies: list[BodyHandle], joints: list[JointHandle]) -> None:
        #: Per watched joint: (the DART joint, its child node, +1 when that is the joint's first body else -1,
        #: the first body's node).
        self._watched: list[tuple[Any, Any, float, Any]] = []
        index = {j.name: k for k, j in enumerate(world.joints)}
        for name in world.reaction_joints:
            handle = joints[index[name]]
            first = bodies[world.body_index(handle.spec.body)].node
            child = handle.joint.getChildBodyNode()
            self._watched.append((handle.joint, child, 1.0 if child.getName() == first.getName() else -1.0, first))

    def __len__(self) -> int:
        return len(self._watched)

    def now(self) -> list[float]:
        """The watched joints' wrenches on their first bodies after this engine step: DART's body force of the
        child (``getWrenchToChildBodyNode`` in the child's own frame: torque and force at its origin, the
        constraint impulses / h included), turned to world axes, moved to the first body's centre of mass.
        DART's body force is the wrench the child transmits to the joint, the opposite of the one it gets
        (a body held at rest reads F = m g down, docs/conformance.md case 19): hence the minus."""
        out: list[float] = []
        for joint, child, sign, first in self._watched:
            wrench = np.asarray(joint.getWrenchToChildBodyNode(child))
            pose = child.getWorldTransform()
            turn, origin = np.asarray(pose.rotation()), np.asarray(pose.translation())
            force = -sign * (turn @ wrench[3:])
            torque = -sign * (turn @ wrench[:3]) + np.cross(origin - np.asarray(first.getCOM()), force)
            out.extend((*force, *torque))
        return out
