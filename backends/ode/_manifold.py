"""The contacts of a colliding pair that involves a triangle mesh (a hull or a static mesh): distinct, four at most.

ODE's trimesh-plane collider makes a contact per triangle and vertex below the plane, so a touching vertex
comes once for each triangle around it: pybullet_data's laikago landing gave its foot's tip vertex 6 to 8
identical contacts and its thigh's hull 48 contacts at 8 distinct vertices, 48 normal rows and 96 friction
rows on one rigid body (rank 6 at most), identical rows only the world's CFM keeps apart. Dantzig's LCP in
float32 then gave up steps ("LCP internal error, s <= 0") and the energy watchdog stopped the run (a lower leg
gained 16 J in one landing). Identical contacts are one contact: each distinct point is kept once. Past four
distinct points a pair keeps four, as the engines the others build from the same hull do (Bullet's contact
manifold holds four, the deepest and those spanning the largest area; MuJoCo's plane-mesh collider the
deepest vertex and up to three more): the deepest, the farthest from it, the farthest from their line, and the
one adding the most area (the sum of the triangles it makes with those three, twice the hull area of the
four for coplanar points). Primitive pairs keep ODE's own contacts (at most 12 here, box-cylinder), and so
does a cylinder's prism stand-in (``_colliders``), which stands for a primitive.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: the contacts a mesh pair keeps (Bullet's manifold size; MuJoCo's plane-mesh: 1 + maxplanemesh = 4)
MESH_CONTACTS = 4


class ReducedEntry:
    """An ``OdeCollisionEntry`` with only the kept contact geoms (the same getters the collider reads)."""

    __slots__ = ("_entry", "_geoms")

    def __init__(self, entry: Any, geoms: list[Any]) -> None:
        self._entry, self._geoms = entry, geoms

    def getGeom1(self) -> Any:  # noqa: N802 - panda3d's getter names
        return self._entry.getGeom1()

    def getGeom2(self) -> Any:  # noqa: N802
        return self._entry.getGeom2()

    def getContactGeoms(self) -> list[Any]:  # noqa: N802
        return self._geoms

    def getNumContacts(self) -> int:  # noqa: N802
        return len(self._geoms)


def reduce_contacts(entry: Any) -> Any:
    """``entry`` itself when its contacts are distinct and at most :data:`MESH_CONTACTS`, else a
    :class:`ReducedEntry` of the kept ones (module docstring)."""
    geoms = entry.getContactGeoms()
    if len(geoms) < 2:
        return entry
    kept = spread([tuple(g.getPos()) for g in geoms], [float(g.getDepth()) for g in geoms])
    return entry if len(kept) == len(geoms) else ReducedEntry(entry, [geoms[k] for k in kept])


def spread(points: list[tuple[float, float, float]], depths: list[float]) -> list[int]:
    """Indices (ascending: ODE's order) of the contacts kept: one per distinct point (the first in ODE's order),
    and of more than four distinct points the deepest, the farthest from it, the farthest from their line and
    the one adding the most area (ties: the first in ODE's order)."""
    distinct = sorted({p: k for k, p in reversed(list(enumerate(points)))}.values())
    if len(distinct) <= MESH_CONTACTS:
        return sorted(distinct)
    p = np.asarray([points[k] for k in distinct], float)
    first = int(np.argmax([depths[k] for k in distinct]))
    second = int(np.argmax(np.sum((p - p[first]) ** 2, axis=1)))
    third = int(np.argmax(_area(p, p[first], p[second])))
    a, b, c = p[first], p[second], p[third]
    fourth = int(np.argmax(_area(p, a, b) + _area(p, a, c) + _area(p, b, c)))
    return sorted({distinct[k] for k in (first, second, third, fourth)})


def _area(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Twice the area of each triangle (p_k, a, b)."""
    return np.linalg.norm(np.cross(p - a, b - a), axis=1)
