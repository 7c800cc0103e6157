"""A joint's reaction: the wrench it applies to its first body, as the expressions read it.

The engine gives, per watched joint (``CompiledWorld.reaction_joints``), the force ``F`` and the torque
``tau_c`` about the first body's centre of mass, world frame, the mean over the last step
(``Backend.joint_reactions``, backends/base.py). The runner moves the torque to the joint's anchor, which
moves with the body (its position in the body frame is fixed at the start): ``tau_a = tau_c + (c - a) x F``
with ``c = p + R com`` and ``a = p + R a_b``. ``<joint>.reaction.force``/``.torque`` are those in world axes;
``.force_body``/``.torque_body`` the same wrench in the first body's axes (``R^T F``, ``R^T tau_a``): what a
force/torque sensor between the joint and the body reads.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from backends.geometry import quat_matrices
from backends.types import BodyStates, CompiledWorld

__all__ = ["reaction_getter"]

_AXES = {"x": 0, "y": 1, "z": 2}


def reaction_getter(
    world: CompiledWorld, joint: str, vector: str, component: str, read: Callable[[], tuple[BodyStates, np.ndarray]]
) -> Callable[[], float]:
    """A getter of ``<joint>.reaction.<vector>.<component>``; ``read()`` gives the states and the reactions."""
    row = world.reaction_joints.index(joint)
    spec = next(j for j in world.joints if j.name == joint)
    body = world.body_index(spec.body)
    start = world.bodies[body]
    r0 = quat_matrices(start.quat)
    anchor_b = r0.T @ (np.asarray(spec.anchor, float) - np.asarray(start.pos, float))  # fixed in the body
    lever_b = np.asarray(start.com, float) - anchor_b  # c - a, in the body's axes
    col = _AXES[component]
    turned, torque = vector.endswith("_body"), vector.startswith("torque")

    def value() -> float:
        states, reactions = read()
        force = reactions[row, 0:3]
        rot = quat_matrices(states.quat[body])
        if torque:
            out = reactions[row, 3:6] + np.cross(rot @ lever_b, force)
        else:
            out = force
        return float((rot.T @ out)[col] if turned else out[col])

    return value
