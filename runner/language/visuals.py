"""What a model file draws: URDF `<visual>` elements and MJCF's visible geoms, as placed shapes in the link frame.

The engines never see these (they collide with :attr:`LinkDesc.shapes`); the trace's scene, the report's
pictures, the Rerun export and the viewer draw them (runner.trace.scene). A mesh is kept as its triangles
(the file's, scaled; MuJoCo's compiled mesh for MJCF), at most :data:`MAX_TRIANGLES` per mesh and
:data:`MAX_MODEL_TRIANGLES` per model: a larger one is simplified by vertex clustering on the finest grid
(doubling) that keeps it under the bound (deterministic: no randomness, sorted cells), so a trace stays
small and byte-identical from run to run.

Colours: URDF, the visual's `<material>` (its own `<color>` or a robot-level material by name), else the
mesh file's own colour (OBJ `.mtl`, DAE material), else none (the link's colour). MJCF, the geom's rgba,
or its material's when the geom keeps the default rgba (MuJoCo's rule). A geom is drawn when MuJoCo's
viewer draws it by default (group 0, 1 or 2) and is not fully transparent.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import Mesh, PlacedShape, Rgba, Shape, ShapeKind
from runner.language.robot_desc import ModelFileError, quat4, quat_from_matrix, resolve_package, vec

__all__ = [
    "MAX_MODEL_TRIANGLES",
    "MAX_TRIANGLES",
    "MJCF_VISIBLE_GROUPS",
    "mjcf_visuals",
    "simplified",
    "urdf_visuals",
    "within_budget",
]

#: triangles kept per visual mesh (KUKA iiwa's largest link mesh has 3,038; the trace stores each once)
MAX_TRIANGLES = 5000
#: triangles kept per model: above it every mesh is simplified further, in proportion (about 2.4 MB of trace)
MAX_MODEL_TRIANGLES = 100_000
#: geom groups MuJoCo's viewer shows by default (mjvOption.geomgroup: 1, 1, 1, 0, 0, 0)
MJCF_VISIBLE_GROUPS = (0, 1, 2)
_MJCF_DEFAULT_RGBA = (0.5, 0.5, 0.5, 1.0)
ScaleOf = Callable[[Any, Path, int], tuple[float, float, float]]
GeomShape = Callable[[Any, int, Any], Shape | None]


def simplified(vertices: np.ndarray, faces: np.ndarray, limit: int = MAX_TRIANGLES) -> tuple[np.ndarray, np.ndarray]:
    """``vertices`` and ``faces`` with at most ``limit`` faces: unchanged when under it, else the vertices
    clustered on a grid (each cell's vertices become their mean; faces that collapse are dropped), the grid
    doubled from 1/256 of the largest extent until the faces fit."""
    vertices, faces = np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(faces) <= limit or not len(vertices):
        return vertices, faces
    low = vertices.min(axis=0)
    cell = max(float((vertices.max(axis=0) - low).max()), 1e-9) / 256.0
    while True:
        keys = np.floor((vertices - low) / cell).astype(np.int64)
        cells, inverse = np.unique(keys, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        merged = faces_of(inverse[faces])
        if len(merged) <= limit or len(cells) <= 4:
            sums = np.zeros((len(cells), 3))
            np.add.at(sums, inverse, vertices)
            counts = np.bincount(inverse, minlength=len(cells)).reshape(-1, 1)
            return sums / counts, merged
        cell *= 2.0


def faces_of(faces: np.ndarray) -> np.ndarray:
    """``faces`` without collapsed triangles (two corners in one cell) or repeats, first occurrence kept."""
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces = faces[keep]
    if not len(faces):
        return faces
    _, first = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
    return faces[np.sort(first)]


def _mesh(vertices: np.ndarray, faces: np.ndarray, source: str) -> Mesh:
    v, f = simplified(vertices, faces)
    return Mesh(vertices=tuple(vec(p) for p in v), faces=tuple((int(a), int(b), int(c)) for a, b, c in f),
                source=source)  # fmt: skip


def within_budget(links: list[Any], budget: int = MAX_MODEL_TRIANGLES) -> list[Any]:
    """``links`` (LinkDesc) with their visual meshes simplified in proportion when they hold more than ``budget``
    triangles together (each keeps at least 100)."""
    from dataclasses import replace

    total = sum(len(v.shape.mesh.faces) for link in links for v in link.visuals if v.shape.mesh is not None)
    if total <= budget:
        return links
    out = []
    for link in links:
        visuals = []
        for v in link.visuals:
            mesh = v.shape.mesh
            if mesh is not None:
                limit = max(100, len(mesh.faces) * budget // total)
                vertices, faces = simplified(np.asarray(mesh.vertices), np.asarray(mesh.faces), limit)
                mesh = Mesh(tuple(vec(p) for p in vertices), tuple((int(a), int(b), int(c)) for a, b, c in faces),
                            mesh.source)  # fmt: skip
                v = replace(v, shape=replace(v.shape, mesh=mesh))
            visuals.append(v)
        out.append(replace(link, visuals=tuple(visuals)))
    return out


# ---- URDF --------------------------------------------------------------------------------------------------------


def _file_colour(loaded: Any) -> Rgba | None:
    """The mesh file's own colour (a face-coloured mesh's main colour, a material's diffuse), if any."""
    visual = getattr(loaded, "visual", None)
    kind = getattr(visual, "kind", None)
    rgba = None
    if kind == "face" or kind == "vertex":
        rgba = np.asarray(getattr(visual, "main_color", ()), dtype=np.float64) / 255.0
    elif kind == "texture":
        material = getattr(visual, "material", None)
        main = getattr(material, "main_color", None)
        rgba = np.asarray(main, dtype=np.float64) / 255.0 if main is not None else None
    if rgba is None or len(rgba) < 4:
        return None
    return (float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3]))


_Cache = dict[tuple[str, tuple[float, float, float]], tuple[Mesh, Rgba | None]]


def _load(path: Path, scale: tuple[float, float, float], file: Path, line: int, cache: _Cache
          ) -> tuple[Mesh, Rgba | None]:  # fmt: skip
    key = (str(path), scale)
    if key in cache:
        return cache[key]
    import trimesh

    try:
        loaded = trimesh.load(str(path), force="mesh", process=True)
    except Exception as exc:  # noqa: BLE001 - trimesh raises many types for unreadable files; all mean "bad mesh"
        raise ModelFileError(file, line, f"cannot read the visual mesh {path.name}: {exc}") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ModelFileError(file, line, f"the visual mesh {path.name} holds no triangles")
    vertices = np.asarray(loaded.vertices, dtype=float) * np.asarray(scale, dtype=float)
    faces = np.asarray(loaded.faces, dtype=np.int64)
    if float(np.prod(np.sign(scale))) < 0:  # a mirroring scale turns faces inside out: keep them outward
        faces = faces[:, ::-1]
    cache[key] = (_mesh(vertices, faces, path.name), _file_colour(loaded))
    return cache[key]


def _material_colour(visual: Any, materials: dict[str, Rgba]) -> Rgba | None:
    material = visual.material
    if material is None:
        return None
    rgba = material.color.rgba if material.color is not None else materials.get(material.name or "")
    if rgba is None:
        return None
    return (float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3]))


def urdf_visuals(link: Any, element: Any, file: Path, materials: dict[str, Rgba], package_root: Path | None,
                 cache: dict[Any, Any], notes: list[str], scale_of: ScaleOf) -> tuple[PlacedShape, ...]:  # fmt: skip
    """The `<visual>`s of one yourdfpy link (``element``: its lxml `<link>`, for lines and capsules), in the link
    frame. A visual whose geometry nothing draws (an empty `<geometry>`) is left out; one whose mesh cannot be
    read is left out with a note (pybullet loads such a model and warns; it changes no dynamics).
    ``scale_of``: the URDF reader's mesh scale rule (runner.language.urdf_shapes.mesh_scale)."""

    elements = element.findall("visual") if element is not None else []
    out = []
    for k, visual in enumerate(link.visuals):
        source = elements[k] if k < len(elements) else None
        line = (source.sourceline or 0) if source is not None else 0
        g = visual.geometry
        colour = _material_colour(visual, materials)
        if g is None:
            continue
        if g.box is not None:
            shape = Shape(ShapeKind.BOX, size=vec(g.box.size))
        elif g.sphere is not None:
            shape = Shape(ShapeKind.SPHERE, radius=float(g.sphere.radius))
        elif g.cylinder is not None:
            capsule = source is not None and source.find("geometry/capsule") is not None
            kind = ShapeKind.CAPSULE if capsule else ShapeKind.CYLINDER
            shape = Shape(kind, radius=float(g.cylinder.radius), length=float(g.cylinder.length))
        elif g.mesh is not None:
            mesh_element = source.find("geometry/mesh") if source is not None else None
            line = (mesh_element.sourceline or line) if mesh_element is not None else line
            try:
                target = resolve_package(g.mesh.filename, package_root, file, line)
                mesh, own = _load(target, scale_of(g.mesh.scale, file, line), file, line, cache)
            except ModelFileError as exc:
                notes.append(f"link `{link.name}`: a visual is not drawn ({exc.message})")
                continue
            shape, colour = Shape(ShapeKind.TRIMESH, mesh=mesh), colour or own
        else:
            continue
        origin = np.asarray(visual.origin) if visual.origin is not None else np.eye(4)
        out.append(PlacedShape(shape, vec(origin[:3, 3]), quat_from_matrix(origin[:3, :3]), colour))
    return tuple(out)


# ---- MJCF --------------------------------------------------------------------------------------------------------


def _mjcf_shape(model: Any, g: int, mujoco: Any, geom_shape: GeomShape) -> Shape | None:
    """A visible geom's shape: primitives as they are (``geom_shape``), a plane at its size (0: infinite), meshes
    as MuJoCo compiled them; None for kinds drawn by nothing here (height field, SDF)."""
    t = mujoco.mjtGeom
    kind, size = int(model.geom_type[g]), model.geom_size[g]
    if kind == t.mjGEOM_PLANE:
        return Shape(ShapeKind.PLANE, size=(2.0 * float(size[0]), 2.0 * float(size[1]), 0.0))
    if kind == t.mjGEOM_MESH:
        m = int(model.geom_dataid[g])
        v0, nv = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
        f0, nf = int(model.mesh_faceadr[m]), int(model.mesh_facenum[m])
        vertices = np.asarray(model.mesh_vert[v0 : v0 + nv], dtype=float)
        faces = np.asarray(model.mesh_face[f0 : f0 + nf], dtype=np.int64)
        return Shape(ShapeKind.TRIMESH, mesh=_mesh(vertices, faces, model.mesh(m).name or f"mesh_{m}"))
    return geom_shape(model, g, mujoco)


def _mjcf_colour(model: Any, g: int) -> Rgba:
    rgba = tuple(float(c) for c in model.geom_rgba[g])
    material = int(model.geom_matid[g])
    if material >= 0 and all(abs(a - b) < 1e-6 for a, b in zip(rgba, _MJCF_DEFAULT_RGBA, strict=True)):
        rgba = tuple(float(c) for c in model.mat_rgba[material])
    return (rgba[0], rgba[1], rgba[2], rgba[3])


def mjcf_visuals(model: Any, body: int, mujoco: Any, geom_shape: GeomShape) -> tuple[PlacedShape, ...]:
    """The geoms of MuJoCo body ``body`` that MuJoCo's viewer draws by default, in the body frame;
    ``geom_shape``: the MJCF reader's shape of a primitive geom (runner.language.mjcf_collision.geom_shape)."""
    out = []
    first = int(model.body_geomadr[body])
    for g in range(first, first + int(model.body_geomnum[body])):
        colour = _mjcf_colour(model, g)
        if int(model.geom_group[g]) not in MJCF_VISIBLE_GROUPS or colour[3] <= 0.0:
            continue
        shape = _mjcf_shape(model, g, mujoco, geom_shape)
        if shape is not None:
            out.append(PlacedShape(shape, vec(model.geom_pos[g]), quat4(model.geom_quat[g]), colour))
    return tuple(out)
