"""A URDF link's collision geometry as shapes: primitives, and mesh files read (scaled, within the mesh limits)
as their triangles or convex hulls."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from backends.types import Mesh, Shape, ShapeKind
from runner.language.mesh_limits import check_mesh_counts, check_mesh_file
from runner.language.model_numbers import check_vertices
from runner.language.robot_desc import ModelFileError, resolve_package, vec


def load_mesh(path: Path, scale: tuple[float, float, float], file: Path, line: int, hull: bool, near: str = "") -> Mesh:
    """The mesh file's triangles (scaled), or their convex hull; a file beyond the mesh limits is refused
    before it is read (runner.language.mesh_limits), a vertex not finite or beyond +-1e9 m after."""
    import trimesh

    check_mesh_file(path, file, line, near)
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)  # processing drops NaN vertices unseen
    except Exception as exc:  # noqa: BLE001 - trimesh raises many types for unreadable files; all mean "bad mesh"
        raise ModelFileError(file, line, f"cannot read the mesh {path.name}: {exc}", near=near) from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ModelFileError(file, line, f"the mesh {path.name} holds no triangles", near=near)
    check_vertices(np.asarray(loaded.vertices) * np.asarray(scale, dtype=float), file, line, path.name)
    loaded.process()  # vertices merged, degenerate faces dropped: as trimesh.load(process=True)
    check_mesh_counts(len(loaded.faces), len(loaded.vertices), path, file, line, near)
    loaded.apply_scale(np.asarray(scale, dtype=float))
    if hull:
        loaded = loaded.convex_hull  # qhull, through trimesh: every vertex of the hull, none moved
    vertices = tuple(vec(v) for v in np.asarray(loaded.vertices, dtype=float))
    faces = tuple((int(a), int(b), int(c)) for a, b, c in np.asarray(loaded.faces))
    return Mesh(vertices=vertices, faces=faces, source=path.name)


def collision_shape(
    geometry: Any, file: Path, package_root: Path | None, mesh_lines: dict[str, int], hull: bool
) -> Shape:
    g = geometry
    if g.box is not None:
        return Shape(ShapeKind.BOX, size=vec(g.box.size))
    if g.sphere is not None:
        return Shape(ShapeKind.SPHERE, radius=float(g.sphere.radius))
    if g.cylinder is not None:
        c = g.cylinder
        return Shape(ShapeKind.CYLINDER, radius=float(c.radius), length=float(c.length))
    mesh = g.mesh
    line = mesh_lines.get(mesh.filename, 0)
    target = resolve_package(mesh.filename, package_root, file, line)
    scale = mesh_scale(mesh.scale, file, line)
    kind = ShapeKind.CONVEX if hull else ShapeKind.TRIMESH
    return Shape(kind, mesh=load_mesh(target, scale, file, line, hull, near=mesh.filename))


def mesh_scale(scale: Any, file: Path, line: int) -> tuple[float, float, float]:
    """`scale` as the loaders read it: none is 1; one number scales every axis; three are x, y, z; pybullet
    reads the first three of more (pybullet_data's racecar writes `scale="1 1 1 1"`)."""
    if scale is None:
        return (1.0, 1.0, 1.0)
    values = np.atleast_1d(np.asarray(scale, dtype=float)).ravel()
    if values.size == 1:
        values = np.repeat(values, 3)
    if values.size < 3 or not np.all(np.isfinite(values[:3])):
        raise ModelFileError(file, line, f"mesh scale {list(values)} is not 1 or 3 numbers", near="scale")
    return vec(values[:3])
