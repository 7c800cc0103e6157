"""What collides in a compiled MJCF model: each geom's shape (an ellipsoid and a mesh as convex hulls), the body
pairs MuJoCo never lets touch, and the file's `<flag>` settings that turn contacts off."""

from __future__ import annotations

from typing import Any

import numpy as np

from backends.types import Mesh, Shape, ShapeKind
from runner.language.robot_desc import vec

#: Subdivisions of the icosphere whose hull stands for an ellipsoid on engines without one: 642 vertices,
#: every one on the ellipsoid; the hull lies inside it by at most 0.3 % of the largest radius.
ELLIPSOID_SUBDIVISIONS = 3


def _hull(points: np.ndarray, source: str) -> Mesh:
    import trimesh

    hull = trimesh.Trimesh(vertices=points, process=True).convex_hull
    vertices = tuple(vec(v) for v in np.asarray(hull.vertices, dtype=float))
    faces = tuple((int(a), int(b), int(c)) for a, b, c in np.asarray(hull.faces))
    return Mesh(vertices=vertices, faces=faces, source=source)


def _ellipsoid(radii: np.ndarray) -> Mesh:
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=ELLIPSOID_SUBDIVISIONS, radius=1.0)
    return _hull(np.asarray(sphere.vertices) * radii, "ellipsoid")


def geom_shape(model: Any, g: int, mujoco: Any) -> Shape | None:
    """A geom's shape in its own frame; None for a kind no engine here collides with (height field, SDF)."""
    kind, size, t = int(model.geom_type[g]), model.geom_size[g], mujoco.mjtGeom
    if kind == t.mjGEOM_PLANE:
        return Shape(ShapeKind.PLANE)
    if kind == t.mjGEOM_SPHERE:
        return Shape(ShapeKind.SPHERE, radius=float(size[0]))
    if kind == t.mjGEOM_CAPSULE:
        return Shape(ShapeKind.CAPSULE, radius=float(size[0]), length=2.0 * float(size[1]))
    if kind == t.mjGEOM_CYLINDER:
        return Shape(ShapeKind.CYLINDER, radius=float(size[0]), length=2.0 * float(size[1]))
    if kind == t.mjGEOM_BOX:
        return Shape(ShapeKind.BOX, size=vec(2.0 * size))
    if kind == t.mjGEOM_ELLIPSOID:
        return Shape(ShapeKind.CONVEX, mesh=_ellipsoid(np.asarray(size, dtype=float)))
    if kind == t.mjGEOM_MESH:  # MuJoCo collides with the hull of the mesh's vertices (in the geom frame)
        mesh = int(model.geom_dataid[g])
        start, count = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        points = np.asarray(model.mesh_vert[start : start + count], dtype=float)
        return Shape(ShapeKind.CONVEX, mesh=_hull(points, model.mesh(mesh).name or f"mesh_{mesh}"))
    return None


def _welded(model: Any, a: int, b: int, mujoco: Any) -> bool:
    """MuJoCo's parent filter (mj_collision), unless the file disables it (`<flag filterparent="disable"/>`)."""
    wa, wb = int(model.body_weldid[a]), int(model.body_weldid[b])
    if wa == wb:
        return True
    if int(model.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT) or not (wa and wb):
        return False
    pa, pb = int(model.body_weldid[model.body_parentid[wa]]), int(model.body_weldid[model.body_parentid[wb]])
    return wa == pb or wb == pa


def excluded_pairs(model: Any, bodies: list[str], mujoco: Any) -> list[tuple[str, str]]:
    """Body pairs (both with collision shapes) that MuJoCo never lets touch: no geom pair passes the
    contype/conaffinity test, MuJoCo's parent filter (on the bodies' weld roots, ``body_weldid``: two bodies
    welded together, or one welded group the parent of the other, neither the world's: humanoid_CMU's neck
    and head overlap across a weld), or an `<exclude>` names them."""
    masks: dict[int, list[tuple[int, int]]] = {}
    for g in range(model.ngeom):
        t, a = int(model.geom_contype[g]), int(model.geom_conaffinity[g])
        if t or a:
            masks.setdefault(int(model.geom_bodyid[g]), []).append((t, a))
    out = []
    ids = sorted(masks)
    for i, a in enumerate(ids):
        for b in ids[i + 1 :]:
            touch = any(ta & ab or tb & aa for ta, aa in masks[a] for tb, ab in masks[b])
            if not touch or _welded(model, a, b, mujoco):
                out.append((bodies[a], bodies[b]))
    for signature in model.exclude_signature:
        a, b = int(signature) >> 16, int(signature) & 0xFFFF
        out.append((bodies[a], bodies[b]))
    return out


def contacts_disabled(model: Any, mujoco: Any) -> bool:
    """`<option><flag contact="disable"/>` (or `constraint="disable"`, which turns contacts off with every other
    constraint): MuJoCo detects no contact at all in the file's model (dm_control's reacher, pendulum, cartpole,
    point_mass, swimmer; acrobot, lqr, fish), so none of its geoms is a collision shape on any engine, with the
    scenario's options (MuJoCo's backend then zeroes their contype and conaffinity, backends/mujoco). It is part
    of the model: without it reacher's arm starts 0.06 m deep in its target sphere and root cylinder, with
    contact normals no joint can move along (docs/robots.md, "MJCF as MuJoCo reads it")."""
    off = int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    return bool(int(model.opt.disableflags) & off)


#: `<flag>` settings read as part of the model (the rest are simulation options: MuJoCo's own with `options:
#: model`, not applied with the scenario's options, where the world's gravity and the engine's solver act)
_MODEL_FLAGS = ("contact", "constraint")


def flag_notes(model: Any, mujoco: Any, line: int) -> list[str]:
    """What the file's `<flag>` disable settings become (docs/robots.md, "MJCF as MuJoCo reads it")."""
    flags = int(model.opt.disableflags)
    named = [n.removeprefix("mjDSBL_").lower() for n in dir(mujoco.mjtDisableBit) if n.startswith("mjDSBL_")]
    off = sorted(n for n in named if flags & int(getattr(mujoco.mjtDisableBit, f"mjDSBL_{n.upper()}")))
    out = []
    kept = [n for n in off if n in _MODEL_FLAGS]
    if kept:
        out.append(f"`<flag {kept[0]}=\"disable\"/>` (line {line}): the file's geoms touch nothing, as MuJoCo runs "
                   "it (its shapes are drawn, not collided)")  # fmt: skip
    rest = [n for n in off if n not in _MODEL_FLAGS and n not in ("autoreset", "filterparent")]
    if rest:
        out.append("with the scenario's options, the file's " + ", ".join(f'`<flag {n}="disable"/>`' for n in rest)
                   + f" (line {line}) not applied: the world's gravity and the engine's own solver act (MuJoCo "
                   "runs them with `world: {options: model}`)")  # fmt: skip
    return out
