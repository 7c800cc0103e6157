"""The PyBullet adapter's per-step reads, with as little Python per body and per contact point as possible.

PyBullet has no batched state call for separate multibodies: every base costs
``getBasePositionAndOrientation`` and ``getBaseVelocity`` (about 1 us each, 0.21 ms for the 100-box
pile [checked]). What is left to trim is the Python around them: the calls are driven by ``map`` and the
floats go straight into one array (0.04 ms for the pile, against 0.08 ms for a loop that concatenates
tuples). ``getContactPoints`` costs about 0.3 us per point itself; for many points the six fields a
contact needs are taken from each point by one ``itemgetter`` and streamed into one array (``fromiter``,
a quarter faster than ``np.array`` of the list of tuples), for a few they go into plain lists, and the
kit groups them per body pair.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import chain, repeat
from operator import itemgetter
from typing import Any

import numpy as np
import pybullet as p

from .._kit.contacts import NUMPY_FROM, contact_point, group_by_pair, sorted_points
from ..types import Contact, ContactPoint
from ._build import Layout
from ._frames import LinkFrames

#: One base's row: position (3), orientation x y z w (4), linear (3) and angular (3) velocity.
ROW = 13

_flat = chain.from_iterable
#: A contact point's bodyUniqueIdA, bodyUniqueIdB, linkIndexA, linkIndexB, contactDistance, normalForce.
_FIELDS_AT = (1, 2, 3, 4, 8, 9)
_FIELDS = itemgetter(*_FIELDS_AT)
#: A link state's worldPosition, worldOrientation (its inertial frame's), worldLinearVelocity, worldAngularVelocity.
_LINK_STATE = itemgetter(0, 1, 6, 7)


def base_rows(c: int, uids: Sequence[int]) -> np.ndarray:
    """(len(uids), 13) states of these multibodies' bases, in PyBullet's order (quaternion x y z w)."""
    n = len(uids)
    poses = map(p.getBasePositionAndOrientation, uids, repeat(c))  # physicsClientId, positionally
    twists = map(p.getBaseVelocity, uids, repeat(c))
    values = _flat(_flat(_flat(zip(poses, twists, strict=True))))  # ((pos, orn), (lin, ang)) -> 13 floats
    return np.fromiter(values, np.float64, ROW * n).reshape(n, ROW)


def link_rows(c: int, uid: int, links: list[int], frames: LinkFrames | None) -> np.ndarray:
    """(len(links), 13) states of these links of one multibody, in the order given: their body frames
    (``frames``: the links' inertial offsets), or their inertial frames as getLinkStates gives them (COM
    position and orientation, linear and angular velocity: fields 0, 1, 6, 7) where ``frames`` is None."""
    states = p.getLinkStates(uid, links, computeLinkVelocity=1, computeForwardKinematics=1, physicsClientId=c)
    if frames is not None:
        return frames.rows(states)
    return np.fromiter(_flat(_flat(map(_LINK_STATE, states))), np.float64, ROW * len(links)).reshape(-1, ROW)


class ContactReader:
    """``getContactPoints`` as one Contact per touching body pair (points with distance <= 0 only:
    PyBullet also reports near points)."""

    def __init__(self, lut: list[list[int]], n_bodies: int) -> None:
        self._lut = lut  # (multibody, link + 1) -> body index
        self._lut_array = np.array(lut, dtype=np.int64)
        self._n = n_bodies

    def __call__(self, points: Sequence[Any]) -> list[Contact]:
        if not points:
            return []
        if len(points) < NUMPY_FROM:  # a few points: plain lists, no array to build
            return self._few(points)
        n = len(points)
        rows = np.fromiter(_flat(map(_FIELDS, points)), np.float64, len(_FIELDS_AT) * n).reshape(n, len(_FIELDS_AT))
        touching = rows[:, 4] <= 0.0
        if not touching.all():
            rows = rows[touching]
        ids = rows[:, :4].astype(np.int64)
        lut = self._lut_array
        first, second = lut[ids[:, 0], ids[:, 2] + 1], lut[ids[:, 1], ids[:, 3] + 1]
        return group_by_pair(self._n, first, second, -rows[:, 4], rows[:, 5])

    def _few(self, points: Sequence[Any]) -> list[Contact]:
        lut = self._lut
        kept = [cp for cp in points if cp[8] <= 0.0]
        first = [lut[cp[1]][cp[3] + 1] for cp in kept]
        second = [lut[cp[2]][cp[4] + 1] for cp in kept]
        return group_by_pair(self._n, first, second, [-cp[8] for cp in kept], [cp[9] for cp in kept])

    def points(self, points: Sequence[Any]) -> list[ContactPoint]:
        """The touching points (the contract's ``contact_points``): at the middle of positionOnA and
        positionOnB, the normal from A to B (PyBullet's contactNormalOnB points from B to A)."""
        lut = self._lut
        out = []
        for cp in points:
            if cp[8] <= 0.0:
                pa, pb, n = cp[5], cp[6], cp[7]
                mid = ((pa[0] + pb[0]) * 0.5, (pa[1] + pb[1]) * 0.5, (pa[2] + pb[2]) * 0.5)
                out.append(contact_point(lut[cp[1]][cp[3] + 1], lut[cp[2]][cp[4] + 1], mid, (-n[0], -n[1], -n[2]),
                                         -cp[8], cp[9]))  # fmt: skip
        return sorted_points(out)


class JointReader:
    """The 1-dof joints (sliders, hinges) read in world joint order and sign: position, rate and the force their
    motor applied, with one ``getJointStates`` call per multibody; NaN (force 0) for every other joint."""

    def __init__(self, joints: int, layout: Layout) -> None:
        self._m, self._layout = joints, layout
        #: the world joints PyBullet holds as one degree of freedom (motors, stops and reads are theirs)
        self.one_dof = [k for k, h in enumerate(layout.joints) if h.dofs == 1]
        uids = sorted({layout.joints[k].uid for k in self.one_dof})
        #: per multibody, its 1-dof joints' links, for one getJointStates call each; then the world joints
        #: those rows are, and their signs
        self._reads = [(u, [layout.joints[k].link for k in self.one_dof if layout.joints[k].uid == u])
                       for u in uids]  # fmt: skip
        order = [k for u in uids for k in self.one_dof if layout.joints[k].uid == u]
        self._order = np.array(order, dtype=np.int64)
        self._sign = np.array([layout.joints[k].sign for k in order], dtype=float)
        #: every joint read, in world order (a robot of hinges and sliders): the read's columns are the arrays
        self._every_joint = order == list(range(joints))

    def states(self, c: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position, velocity, motor force) of every world joint now."""
        m = self._m
        if self._reads:  # one getJointStates per multibody: (q, qd, reaction forces, applied torque)
            states = [s for uid, links in self._reads for s in p.getJointStates(uid, links, physicsClientId=c)]
            rows = np.fromiter(_flat((s[0], s[1], s[3]) for s in states), np.float64, 3 * len(states))
            rows = rows.reshape(-1, 3) * self._sign[:, None]
            if self._every_joint:
                pos, vel, force = np.ascontiguousarray(rows.T)  # three contiguous rows: the same numbers
            else:
                pos, vel, force = np.full(m, np.nan), np.full(m, np.nan), np.zeros(m)
                order = self._order
                pos[order], vel[order], force[order] = rows[:, 0], rows[:, 1], rows[:, 2]
        else:
            pos, vel, force = np.full(m, np.nan), np.full(m, np.nan), np.zeros(m)
        return pos, vel, force

    def motor_torques(self, c: int) -> np.ndarray:
        """The force or torque each 1-dof joint's motor applied in the last engine step (0 for the others)."""
        out = np.zeros(self._m)
        for k in self.one_dof:
            h = self._layout.joints[k]
            out[k] = h.sign * p.getJointState(h.uid, h.link, physicsClientId=c)[3]
        return out
