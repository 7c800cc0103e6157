"""Triangle meshes of the scene's primitives (trimesh builds them), ready for a vertex buffer.

Every mesh comes as unshared triangles: ``vertices`` (3n, 3) and ``normals`` (3n, 3), three rows per
triangle, counter-clockwise seen from outside. Boxes and cylinders are flat-shaded (one normal per face,
crisp edges); spheres are smooth (the normal of the ellipsoid at each vertex). Triangle lists are drawn
as given, both sides, with their own face normals.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import trimesh

from backends.geometry import quat_matrices
from reports.scene3d.model import Primitive

__all__ = ["Mesh", "primitive_mesh"]

SPHERE_SUBDIVISIONS = 3  # icosphere: 1280 triangles
CYLINDER_SECTIONS = 32

Mesh = tuple[np.ndarray, np.ndarray]


@lru_cache(maxsize=8)
def _unit(kind: str) -> trimesh.Trimesh:
    if kind == "cube":
        return trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    if kind == "sphere":
        return trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=0.5)
    if kind == "cylinder":
        return trimesh.creation.cylinder(radius=0.5, height=1.0, sections=CYLINDER_SECTIONS)
    raise ValueError(f"no unit mesh for {kind!r}")


def _flat(vertices: np.ndarray, faces: np.ndarray) -> Mesh:
    tri = vertices[faces]  # (n, 3, 3)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    return tri.reshape(-1, 3), np.repeat(normal, 3, axis=0)


ARROW_SECTIONS = 12
_Z_TO_X = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # turns local z onto x


def _arrow(length: float, shaft: float, head: float) -> tuple[np.ndarray, np.ndarray]:
    """An arrow along +x from the origin, as Foxglove draws one: a shaft (3/4 of the length) and a cone."""
    stem = trimesh.creation.cylinder(radius=shaft / 2, height=0.75 * length, sections=ARROW_SECTIONS)
    stem.apply_translation((0.0, 0.0, 0.375 * length))
    cone = trimesh.creation.cone(radius=head / 2, height=0.25 * length, sections=ARROW_SECTIONS)
    cone.apply_translation((0.0, 0.0, 0.75 * length))
    vertices = np.vstack([stem.vertices, cone.vertices]) @ _Z_TO_X.T
    faces = np.vstack([stem.faces, np.asarray(cone.faces) + len(stem.vertices)])
    return vertices, faces


def primitive_mesh(prim: Primitive) -> Mesh:
    """(vertices, normals) of ``prim`` in its body's frame, its own pose applied; empty for lines."""
    if prim.kind == "lines":
        return np.zeros((0, 3)), np.zeros((0, 3))
    if prim.kind == "arrow":
        vertices, normals = _flat(*_arrow(*prim.size))
    elif prim.kind == "triangles":
        pts = np.asarray(prim.points, float).reshape(-1, 3)
        pts = pts[: len(pts) - len(pts) % 3]
        faces = np.arange(len(pts)).reshape(-1, 3)
        vertices, normals = _flat(pts, faces)
    else:
        unit = _unit(prim.kind)
        scale = np.asarray(prim.size, float)
        scaled = np.asarray(unit.vertices) * scale
        if prim.kind == "sphere":
            grad = np.asarray(unit.vertices) / np.where(scale > 0, scale, 1.0)  # ellipsoid normal ~ v / s^2
            norm = np.linalg.norm(grad, axis=1, keepdims=True)
            smooth = np.divide(grad, norm, out=np.zeros_like(grad), where=norm > 0)
            faces = np.asarray(unit.faces)
            vertices, normals = scaled[faces].reshape(-1, 3), smooth[faces].reshape(-1, 3)
        else:
            vertices, normals = _flat(scaled, np.asarray(unit.faces))
    rot = quat_matrices(prim.quat)
    return vertices @ rot.T + np.asarray(prim.position, float), normals @ rot.T
