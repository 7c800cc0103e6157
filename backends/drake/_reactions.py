"""Joint reactions (``joint:reaction``) from the plant's reaction forces output port.

Drake reports per joint ``F_CJc_Jc``: the spatial force the joint applies to its child body C at the child
frame's origin Jc, expressed in Jc (its constraint, limit and actuation forces together; sampled: the last
discrete update's). The contract wants the wrench on the world joint's first body, in the world frame, the
torque about that body's COM: rotate by Jc's world orientation, negate where the tree hangs the joint from the
first body (sign -1: it is Drake's parent P, which gets -F at the same point), and shift the torque from Jc to
the COM (tau_com = tau_Jc + (p_Jc - p_com) x f). The force is the update's, computed at the poses the update
started from, so it is turned and shifted with those (``before``): measured, the arm of conformance 19 held by
its motor turns 6e-8 rad per step, and with the poses after the update its 19.62 N read 1.17e-6 N sideways.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._build import JointHandle


class Reactions:
    """The watched joints' wrenches on their first bodies, read after an engine step."""

    def __init__(self, plant: Any, context: Any, handles: list[JointHandle], watched: list[int]) -> None:
        self._plant, self._context = plant, context
        self._port = plant.get_reaction_forces_output_port()
        self._rows = []
        for j in watched:
            handle = handles[j]
            joint = handle.joint
            first = joint.child_body() if handle.sign > 0 else joint.parent_body()
            com = first.default_spatial_inertia().get_com()  # in the first body's frame
            self._rows.append((int(joint.index()), joint.frame_on_child(), first, com, handle.sign))
        self._frames: list[tuple[np.ndarray, np.ndarray]] = []

    def before(self) -> None:
        """Keep, before an engine update, each joint's Jc orientation and its lever from the first body's COM."""
        self._frames = []
        for _, frame_jc, first, com, _ in self._rows:
            x_wjc = frame_jc.CalcPoseInWorld(self._context)
            p_com = np.asarray(self._plant.EvalBodyPoseInWorld(self._context, first).multiply(com))
            self._frames.append((x_wjc.rotation().matrix(), np.asarray(x_wjc.translation()) - p_com))

    def read(self) -> np.ndarray:
        """(watched joints, 6) after the update: force then torque about the first body's COM, world frame."""
        forces = self._port.Eval(self._context)
        out = np.zeros((len(self._rows), 6))
        for k, ((index, _, _, _, sign), (rotation, lever)) in enumerate(zip(self._rows, self._frames, strict=True)):
            spatial = forces[index]
            f = sign * (rotation @ np.asarray(spatial.translational()))
            out[k, :3] = f
            out[k, 3:] = sign * (rotation @ np.asarray(spatial.rotational())) + np.cross(lever, f)
        return out
