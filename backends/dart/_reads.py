"""DART's per-step state reads: the free bodies' coordinates in as few dartpy calls as the bindings allow
(turned into quaternions by :func:`rotvec_to_quat`), and the bodies' motion for approach speeds.

A free body is one Skeleton on a FreeJoint (``_build``), read as its positions ([rotation vector,
translation]) and velocities ([angular, linear]). dartpy 6.20 has no world-level state getter (``World``
has no ``getPositions``), does not bind ``Skeleton::Configuration`` (``getConfiguration()`` raises
TypeError), gives ``LinkageCriteria`` no constructor and does not bind ``Group``: none reads several
skeletons at once. A ``Chain`` between the root bodies of two skeletons does: no joint path joins them, so
it is a referential skeleton of just those two bodies, and its ``getPositions``/``getVelocities`` return
both skeletons' 12 coordinates in one call, the same values in the same order as the two skeletons' own
calls [checked: every step of the 100-box pile, equal arrays]; on that pile two calls per body become one
(0.16 -> 0.12 ms per step). Each chain's degrees of freedom are checked when it is made; a pair whose chain
does not hold exactly the two skeletons' coordinates, in order, is read skeleton by skeleton.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import dartpy as dart
import numpy as np

from ..types import BodySpec, Motion
from ._build import BodyHandle

#: A FreeJoint's coordinates.
FREE_DOFS = 6

Read = Callable[[], np.ndarray]


def state_readers(skeletons: Sequence[Any]) -> tuple[list[Read], list[Read]]:
    """Getters of positions and of velocities whose results, concatenated, are the free ``skeletons``' own
    ``getPositions()`` and ``getVelocities()`` concatenated in order (6 values per skeleton)."""
    positions: list[Read] = []
    velocities: list[Read] = []
    for k in range(0, len(skeletons), 2):
        pair = skeletons[k : k + 2]
        chain = _chain(pair[0], pair[1]) if len(pair) == 2 else None
        if chain is None:
            positions += [s.getPositions for s in pair]
            velocities += [s.getVelocities for s in pair]
        else:
            positions.append(chain.getPositions)
            velocities.append(chain.getVelocities)
    return positions, velocities


def _chain(first: Any, second: Any) -> Any | None:
    """The chain reading both skeletons' coordinates in order, or None where it does not."""
    chain = dart.dynamics.Chain(first.getRootBodyNode(), second.getRootBodyNode())
    expected = [(first.getName(), i) for i in range(FREE_DOFS)] + [(second.getName(), i) for i in range(FREE_DOFS)]
    if first.getNumDofs() != FREE_DOFS or second.getNumDofs() != FREE_DOFS or chain.getNumDofs() != len(expected):
        return None
    dofs = [chain.getDof(i) for i in range(len(expected))]
    found = [(dof.getSkeleton().getName(), dof.getIndexInSkeleton()) for dof in dofs]
    return chain if found == expected and first.getName() != second.getName() else None


def row_index(indices: list[int]) -> slice | np.ndarray:
    """Row indices as a slice when they are consecutive (cheaper to assign through), else an array."""
    if indices and indices == list(range(indices[0], indices[-1] + 1)):
        return slice(indices[0], indices[-1] + 1)
    return np.array(indices, dtype=np.intp)


def rotvec_to_quat(rv: np.ndarray) -> np.ndarray:
    """(N, 3) rotation vectors -> (N, 4) unit quaternions (w, x, y, z)."""
    angle = np.sqrt(np.add.reduce(rv * rv, axis=(1,)))  # np.linalg.norm(rv, axis=1) without its checks
    small = angle < 1e-8
    safe = np.where(small, 1.0, angle)
    scale = np.where(small, 0.5 - angle * angle / 48.0, np.sin(0.5 * angle) / safe)
    quat = np.empty((len(rv), 4))
    quat[:, 0], quat[:, 1:] = np.cos(0.5 * angle), rv * scale[:, None]
    return quat


def com_motion(specs: Sequence[BodySpec], bodies: Sequence[BodyHandle], indices: list[int]) -> np.ndarray:
    """(N, 9) rows of these bodies: centre of mass (the body frame's origin), linear and angular velocity
    (zeros for a static body)."""
    rows = np.zeros((len(indices), 9))
    for k, i in enumerate(indices):
        if specs[i].motion is Motion.STATIC:
            continue
        node = bodies[i].node
        rows[k, 0:3] = node.getWorldTransform().translation()
        rows[k, 3:6] = node.getLinearVelocity()
        rows[k, 6:9] = node.getAngularVelocity()
    return rows
