"""Touching body pairs from DART's contact points: the per-step contact read of the DART backend.

``CollisionResult.getContacts()`` lists contact points, each naming two collision objects. Reading a
field of a point through dartpy costs 0.1-0.3 us (a numpy view for a vector), so each field is read
once, one field at a time over all points, by the property's own getter (``fget``, taken from the points'
class: about 10 % cheaper than ``attrgetter``, which goes through the descriptor each time), and the rest
is done on arrays: body pairs from a cache of the collision objects, normal forces as one ``einsum``; the
kit's ``group_by_pair`` then gives each pair's count, deepest depth and summed normal force, the points in
DART's order. This module does not import the engine.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from operator import attrgetter
from typing import Any

import numpy as np

from .._kit import contact_point, group_by_pair, sorted_points
from ..types import Contact, ContactPoint

_FIRST, _SECOND = attrgetter("collisionObject1"), attrgetter("collisionObject2")
_DEPTH, _FORCE, _NORMAL = attrgetter("penetrationDepth"), attrgetter("force"), attrgetter("normal")
_POINT = attrgetter("point")
#: The fields read from each point, in the order of :class:`_Getters`.
_FIELDS = ("collisionObject1", "collisionObject2", "penetrationDepth", "force", "normal")
_Getters = tuple[Callable[[Any], Any], ...]


def _getters(point_class: type) -> _Getters:
    """Each field's getter: the property's ``fget`` where the class has one, else ``attrgetter``."""
    found = (getattr(point_class, name, None) for name in _FIELDS)
    return tuple(
        prop.fget if isinstance(prop, property) and prop.fget else attrgetter(name)
        for prop, name in zip(found, _FIELDS, strict=True)
    )


class ContactReader:
    """Turns DART contact points into one :class:`Contact` per body pair (``a < b``), sorted by (a, b).

    ``n_bodies`` is the number of bodies, ``static`` the indices of the static ones: pairs of two
    static bodies are never reported.
    """

    def __init__(self, n_bodies: int, static: Sequence[int]) -> None:
        self._n = n_bodies
        self._static = np.zeros(n_bodies, dtype=bool)
        self._static[list(static)] = True
        self._object_body: dict[Any, int] = {}
        self._getters: dict[type, _Getters] = {}

    def contacts(self, points: Sequence[Any]) -> list[Contact]:
        """The touching pairs of ``points``: point count, deepest penetration, summed |force . normal|."""
        if not points:
            return []
        first, second, depth, force, normal = self._fields(points)
        lo, hi = self._pair_of_points(tuple(map(first, points)), tuple(map(second, points)))
        depths = np.fromiter(map(depth, points), np.float64, len(points))
        vectors = np.frombuffer(b"".join((*map(force, points), *map(normal, points)))).reshape(2, -1, 3)
        both_static = self._static[lo] & self._static[hi]
        if both_static.any():
            kept = ~both_static
            if not kept.any():
                return []
            lo, hi, depths, vectors = lo[kept], hi[kept], depths[kept], vectors[:, kept]
        normal_force = np.abs(np.einsum("ij,ij->i", vectors[0], vectors[1]))
        return group_by_pair(self._n, lo, hi, depths, normal_force)

    def points(self, points: Sequence[Any]) -> list[ContactPoint]:
        """The contract's ``contact_points``: each point's position, its normal turned to point from object 1
        to object 2 (DART's points from object 2 to object 1), depth and |force . normal|."""
        if not points:
            return []
        first, second, depth, force, normal = self._fields(points)
        a, b = self._bodies(tuple(map(first, points))), self._bodies(tuple(map(second, points)))
        out = []
        for i, j, point in zip(a.tolist(), b.tolist(), points, strict=True):
            if self._static[i] and self._static[j]:
                continue
            n = np.asarray(normal(point), dtype=np.float64)
            out.append(contact_point(i, j, _POINT(point), -n, depth(point), abs(float(np.dot(force(point), n)))))
        return sorted_points(out)

    def pairs(self, points: Sequence[Any]) -> set[tuple[int, int]]:
        """The (a < b) body pairs of ``points``, static pairs included."""
        if not points:
            return set()
        first, second = self._fields(points)[:2]
        lo, hi = self._pair_of_points(tuple(map(first, points)), tuple(map(second, points)))
        return set(zip(lo.tolist(), hi.tolist(), strict=True))

    def approach(self, points: Sequence[Any], motion: Any) -> dict[tuple[int, int], float]:
        """Per (a < b) pair of ``points``: the fastest speed along a point's normal at which its two bodies
        move relative to each other (either sign: a separating point does not bounce anyway).
        ``motion(indices)`` gives those bodies' (N, 9) rows: centre of mass, linear and angular velocity
        (zeros for a static body)."""
        if not points:
            return {}
        first, second = self._bodies(tuple(map(_FIRST, points))), self._bodies(tuple(map(_SECOND, points)))
        vectors = np.frombuffer(b"".join((*map(_POINT, points), *map(_NORMAL, points)))).reshape(2, -1, 3)
        where, normal = vectors[0], vectors[1]
        bodies, index = np.unique(np.concatenate([first, second]), return_inverse=True)
        rows = motion(bodies.tolist())
        ra, rb = rows[index[: len(first)]], rows[index[len(first) :]]
        rel = ra[:, 3:6] + np.cross(ra[:, 6:9], where - ra[:, 0:3])
        rel -= rb[:, 3:6] + np.cross(rb[:, 6:9], where - rb[:, 0:3])
        speed = np.abs(np.einsum("ij,ij->i", rel, normal))
        lo, hi = np.minimum(first, second), np.maximum(first, second)
        out: dict[tuple[int, int], float] = {}
        for a, b, v in zip(lo.tolist(), hi.tolist(), speed.tolist(), strict=True):
            if v > out.get((a, b), -1.0):
                out[(a, b)] = v
        return out

    def _fields(self, points: Sequence[Any]) -> _Getters:
        """The getters for these points' class (one class per engine: looked up once)."""
        kind = type(points[0])
        getters = self._getters.get(kind)
        if getters is None:
            getters = self._getters[kind] = _getters(kind)
        return getters

    def _pair_of_points(self, first: Sequence[Any], second: Sequence[Any]) -> tuple[np.ndarray, np.ndarray]:
        """(lower, higher) body index of every point, from its two collision objects."""
        a, b = self._bodies(first), self._bodies(second)
        return np.minimum(a, b), np.maximum(a, b)

    def _bodies(self, objects: Sequence[Any]) -> np.ndarray:
        """The body indices of collision objects (each object's shape node is named by the index, a compound
        body's shape nodes ``<index>:<k>``).

        Reading the name costs about 7 us; the wrapper objects are cached instead, which keeps them
        alive so that dartpy hands back the same wrapper for the same object on later calls.
        """
        known = self._object_body
        try:
            return np.fromiter(map(known.__getitem__, objects), dtype=np.intp, count=len(objects))
        except KeyError:
            for obj in objects:
                if obj not in known:
                    known[obj] = int(obj.getShapeFrame().getName().partition(":")[0])
            return np.fromiter(map(known.__getitem__, objects), dtype=np.intp, count=len(objects))
