"""The contacts of a Newton engine step as the contract reads them: the touching pairs with their normal force,
and the touching points, from the collision pipeline's ``Contacts`` at the poses the step started from.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._kit import contact_point, group_by_pair, sorted_points
from ..types import Contact, ContactPoint
from ._build import rotate_xyzw


def read_contacts(
    c: Any,
    body_q: np.ndarray,
    owner: np.ndarray,
    body: np.ndarray,
    obs: Any,
    contact_stiffness: float,
    bodies: int,
    points: bool = False,
) -> tuple[list[Contact], list[ContactPoint] | None]:
    """The touching contacts of the engine step just taken (Newton's ``Contacts`` ``c``), at the poses it started
    from (``body_q``), by pair of the ``bodies`` world bodies (``owner``: shape -> world body; ``body``: world
    body -> Newton body); the normal force from XPBD's observables ``obs``, else Featherstone's penalty law
    (``contact_stiffness``). ``points``: also its touching points (``contact_points``: halfway between the two
    shapes' surfaces), else None."""
    count = int(c.rigid_contact_count.numpy()[0])
    if count == 0:
        return [], None
    shape0, shape1 = c.rigid_contact_shape0.numpy()[:count], c.rigid_contact_shape1.numpy()[:count]
    a, b = owner[shape0], owner[shape1]
    p0 = _to_world(body_q, body[a], c.rigid_contact_point0.numpy()[:count])
    p1 = _to_world(body_q, body[b], c.rigid_contact_point1.numpy()[:count])
    normal = c.rigid_contact_normal.numpy()[:count].astype(float)
    margin = c.rigid_contact_margin0.numpy()[:count] + c.rigid_contact_margin1.numpy()[:count]
    separation = np.einsum("ij,ij->i", normal, p1 - p0) - margin
    touching = separation <= 0.0
    if obs is not None:
        force = np.abs(np.einsum("ij,ij->i", obs.contact_f.numpy()[:count, :3].astype(float), normal))
    else:  # Featherstone: the penalty law's elastic part (the damping part is zero at rest)
        force = contact_stiffness * np.maximum(0.0, -separation)
    keep = np.flatnonzero(touching)
    found: list[ContactPoint] | None = None
    if points:
        middle = 0.5 * (p0 + c.rigid_contact_margin0.numpy()[:count, None] * normal
                        + p1 - c.rigid_contact_margin1.numpy()[:count, None] * normal)  # fmt: skip
        found = sorted_points([contact_point(int(a[r]), int(b[r]), middle[r], normal[r], -float(separation[r]),
                                             float(force[r])) for r in keep])  # fmt: skip
    return group_by_pair(bodies, a[keep], b[keep], -separation[keep], force[keep]), found


def _to_world(body_q: np.ndarray, bodies: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Contact points in their bodies' frames (static shapes: the world's) to the world frame."""
    out = points.astype(float).copy()
    for r, k in enumerate(bodies):
        if k >= 0:
            out[r] = body_q[k, :3] + rotate_xyzw(body_q[k, 3:], points[r])
    return out
