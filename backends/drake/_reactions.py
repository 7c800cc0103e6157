"""Joint reactions (``joint:reaction``) from the plant's reaction forces output port.

Drake reports per joint ``F_CJc_Jc``: the spatial force the joint applies to its child body C at the child
frame's origin Jc, expressed in Jc (its constraint, limit and actuation forces together; sampled: the last
discrete update's). The contract wants the wrench on the world joint's first body, in the world frame, the
torque about that body's COM: rotate by Jc's world orientation, negate where the tree hangs the joint from the
first body (sign -1: it is Drake's parent P, which gets -F at the same point), and shift the torque from Jc to
the COM (tau_com = tau_Jc + (p_Jc - p_com) x f).
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

    def read(self) -> np.ndarray:
        """(watched joints, 6): force then torque about the first body's COM, world frame."""
        forces = self._port.Eval(self._context)
        out = np.zeros((len(self._rows), 6))
        for k, (index, frame_jc, first, com, sign) in enumerate(self._rows):
            x_wjc = frame_jc.CalcPoseInWorld(self._context)
            rotation = x_wjc.rotation().matrix()
            spatial = forces[index]
            f = sign * (rotation @ np.asarray(spatial.translational()))
            tau = sign * (rotation @ np.asarray(spatial.rotational()))
            p_com = np.asarray(self._plant.EvalBodyPoseInWorld(self._context, first).multiply(com))
            out[k, :3] = f
            out[k, 3:] = tau + np.cross(np.asarray(x_wjc.translation()) - p_com, f)
        return out
