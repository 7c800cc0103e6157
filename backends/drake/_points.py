"""Contact points (``contacts:points``) from the plant's ContactResults of an engine step.

A point contact (``PointPairContactInfo``) is one point: the middle of its two witness points, Drake's normal
(``nhat_BA_W``, from B into A) turned to run from body a to body b, its depth, and the normal component of its
force. A hydroelastic contact (``HydroelasticContactInfo``) is a contact surface, and Drake's discrete solver
makes one contact of each of its faces at the face's centroid (SAP's hydroelastic discretisation): so one point
per face, its normal the face's (out of N into M) turned to run from a to b. Drake reports the surface's total
force only, so the pair's normal force is shared among the faces by their pressure times area (the pressure
field evaluated at the centroid): the points sum to the pair's ``contacts()`` force. Drake holds no depth per
face: each face's point carries the pair's deepest penetration (SceneGraph's point-pair query).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..types import ContactPoint


def _pair(owner: dict[int, int], id_a: Any, id_b: Any) -> tuple[int, int, float]:
    """(a, b, s): the bodies ordered, s = +1 when Drake's first geometry is body a's, else -1."""
    first, second = owner[id_a.get_value()], owner[id_b.get_value()]
    return (first, second, 1.0) if first < second else (second, first, -1.0)


def _point(a: int, b: int, pos: Any, normal: Any, depth: float, force: float) -> ContactPoint:
    p, n = np.asarray(pos, dtype=float), np.asarray(normal, dtype=float)
    return ContactPoint(a, b, (float(p[0]), float(p[1]), float(p[2])), (float(n[0]), float(n[1]), float(n[2])),
                        float(depth), float(force))  # fmt: skip


def read_points(
    results: Any, owner: dict[int, int], deepest: dict[tuple[int, int], float] | None
) -> list[ContactPoint]:
    """Every contact point of ``results`` (one engine step's ContactResults), sorted by pair, Drake's order within."""
    points: list[ContactPoint] = []
    for k in range(results.num_point_pair_contacts()):
        info = results.point_pair_contact_info(k)
        pair = info.point_pair()
        a, b, s = _pair(owner, pair.id_A, pair.id_B)
        nhat = np.asarray(pair.nhat_BA_W)  # from B into A: from A to B is -nhat
        force = abs(float(np.dot(info.contact_force(), nhat)))
        middle = (np.asarray(pair.p_WCa) + np.asarray(pair.p_WCb)) / 2.0
        points.append(_point(a, b, middle, -s * nhat, float(pair.depth), force))
    for k in range(results.num_hydroelastic_contacts()):
        info = results.hydroelastic_contact_info(k)
        surface = info.contact_surface()
        a, b, s = _pair(owner, surface.id_M(), surface.id_N())
        field = surface.tri_e_MN() if surface.is_triangle() else surface.poly_e_MN()
        faces = range(surface.num_faces())
        centroids = [np.asarray(surface.centroid(f)) for f in faces]
        normals = [np.asarray(surface.face_normal(f)) for f in faces]  # out of N, into M
        weights = np.array([max(float(field.EvaluateCartesian(f, c)), 0.0) * surface.area(f)
                            for f, c in zip(faces, centroids, strict=True)])  # fmt: skip
        area_normal = sum((surface.area(f) * normals[f] for f in faces), np.zeros(3))
        norm = float(np.linalg.norm(area_normal))
        total = abs(float(np.dot(info.F_Ac_W().translational(), area_normal / norm))) if norm > 0.0 else 0.0
        shares = weights / weights.sum() if weights.sum() > 0.0 else np.full(len(weights), 1.0 / max(len(weights), 1))
        depth = (deepest or {}).get((a, b), math.nan)
        for f in faces:  # M is body a's (s = +1): from a to b is from M to N, against the face normal
            points.append(_point(a, b, centroids[f], -s * normals[f], depth, total * float(shares[f])))
    points.sort(key=lambda p: (p.a, p.b))  # stable: the engine's order within a pair
    return points
