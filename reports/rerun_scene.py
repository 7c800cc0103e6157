"""A trace's scene as Rerun archetypes: one entity per body or robot link, its shapes in its own frame.

The shapes are the trace's /scene entities (:func:`reports.scene3d.model.scene_model`): a body's visual
(``body/<name>``: a robot link's visual meshes, else its shape) is logged at ``world/<name>``, its collision
solids (``solid/<name>/...``) and collision shapes (``collision/<name>``, /scene/collision) together at
``world/<name>/collision`` (hidden by the blueprint), each joint drawn on it (``joint/<joint>``: its axis
as ``Arrows3D``, its anchor as a small ellipsoid) at ``world/<name>/joint/<joint>``. Foxglove primitives
map one to one: cubes to ``Boxes3D``, spheres to ``Ellipsoids3D``, cylinders to ``Cylinders3D`` (both along
local z), a capsule body's cylinder and end spheres to one ``Capsules3D``, triangle lists (meshes, convex
hulls) to one ``Mesh3D`` per entity with per-vertex colours, lines to ``LineStrips3D``, arrows to
``Arrows3D``. Shapes are logged at the time the trace sets them (t = 0, and when an interval rescales a
body), so a later update replaces the earlier one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from reports.scene3d.model import EntityVisual, Primitive, SceneModel

__all__ = ["entity_archetypes", "scene_entities"]

WORLD = "world"


def _rotate(q: Sequence[float], v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` (N, 3) turned by the quaternion ``q`` (w, x, y, z)."""
    w, x, y, z = (float(c) for c in q)
    r = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip
    return np.asarray(v, dtype=float).reshape(-1, 3) @ r.T


def _xyzw(q: Sequence[float]) -> list[float]:
    return [float(q[1]), float(q[2]), float(q[3]), float(q[0])]


def _placed_points(p: Primitive) -> np.ndarray:
    return _rotate(p.quat, np.asarray(p.points, dtype=float).reshape(-1, 3)) + np.asarray(p.position)


def _capsule(prims: Sequence[Primitive]) -> tuple[float, float, np.ndarray, list[float]] | None:
    """(length, radius, base point, quaternion x y z w) when ``prims`` are one capsule as the trace draws it:
    a cylinder along local z and a sphere of its radius on each end."""
    cylinders = [p for p in prims if p.kind == "cylinder"]
    spheres = [p for p in prims if p.kind == "sphere"]
    if len(cylinders) != 1 or len(spheres) != 2 or len(prims) != 3:
        return None
    c = cylinders[0]
    radius, length = c.size[0] / 2, c.size[2]
    if any(abs(s.size[0] / 2 - radius) > 1e-12 for s in spheres):
        return None
    base = np.asarray(c.position) + _rotate(c.quat, np.array([[0.0, 0.0, -length / 2]]))[0]
    return length, radius, base, _xyzw(c.quat)


def entity_archetypes(entity: EntityVisual, capsule: bool = False) -> list[Any]:
    """The Rerun archetypes drawing ``entity``'s primitives in its body's frame (``capsule``: the body's shape
    is a capsule, drawn as one when its primitives are the trace's cylinder and two spheres)."""
    import rerun as rr

    prims = list(entity.primitives)
    out: list[Any] = []
    cap = _capsule(prims) if capsule else None
    if cap is not None:
        length, radius, base, quat = cap
        out.append(rr.Capsules3D(lengths=[length], radii=[radius], translations=[base], quaternions=[quat],
                                 colors=[prims[0].rgba]))  # fmt: skip
        return out
    by_kind: dict[str, list[Primitive]] = {}
    for p in prims:
        by_kind.setdefault(p.kind, []).append(p)
    if cubes := by_kind.get("cube"):
        out.append(rr.Boxes3D(half_sizes=[np.asarray(p.size) / 2 for p in cubes], centers=[p.position for p in cubes],
                              quaternions=[_xyzw(p.quat) for p in cubes], colors=[p.rgba for p in cubes],
                              fill_mode="solid"))  # fmt: skip
    if spheres := by_kind.get("sphere"):
        out.append(rr.Ellipsoids3D(half_sizes=[np.asarray(p.size) / 2 for p in spheres],
                                   centers=[p.position for p in spheres], quaternions=[_xyzw(p.quat) for p in spheres],
                                   colors=[p.rgba for p in spheres], fill_mode="solid"))  # fmt: skip
    if cylinders := by_kind.get("cylinder"):
        out.append(rr.Cylinders3D(lengths=[p.size[2] for p in cylinders], radii=[p.size[0] / 2 for p in cylinders],
                                  centers=[p.position for p in cylinders],
                                  quaternions=[_xyzw(p.quat) for p in cylinders], colors=[p.rgba for p in cylinders],
                                  fill_mode="solid"))  # fmt: skip
    if triangles := [p for p in by_kind.get("triangles", []) if len(p.points) >= 3]:
        points = [_placed_points(p)[: len(p.points) // 3 * 3] for p in triangles]
        colors = np.concatenate([np.tile(np.asarray(p.rgba, dtype=np.float32), (len(v), 1))
                                 for p, v in zip(triangles, points, strict=True)])  # fmt: skip
        out.append(rr.Mesh3D(vertex_positions=np.concatenate(points), vertex_colors=colors))
    if arrows := by_kind.get("arrow"):
        vectors = [_rotate(p.quat, np.array([[p.size[0], 0.0, 0.0]]))[0] for p in arrows]
        out.append(rr.Arrows3D(origins=[p.position for p in arrows], vectors=vectors,
                               radii=[p.size[1] / 2 for p in arrows], colors=[p.rgba for p in arrows]))  # fmt: skip
    if lines := [p for p in by_kind.get("lines", []) if p.points]:
        strips = []
        for p in lines:
            pts = _placed_points(p)
            strips.append(np.vstack([pts, pts[:1]]) if p.closed else pts)
        out.append(rr.LineStrips3D(strips, colors=[p.rgba for p in lines]))
    return out


def scene_entities(model: SceneModel) -> list[tuple[float, str, list[Any]]]:
    """(time, entity path, archetypes) for every scene update of every body, in time order. A body's visual is
    at ``world/<body>``, its collision solids together at ``world/<body>/collision``; an entity the trace
    deletes is logged as ``Clear``."""
    import rerun as rr

    out: list[tuple[float, str, list[Any]]] = []
    known = set(model.bodies)
    for t, update in model.updates:
        solids: dict[str, list[EntityVisual]] = {}
        for key, visual in update.items():
            if visual is None:
                out.append((t, _path_of(key), [rr.Clear(recursive=False)]))
            elif visual.body not in known:
                continue
            elif visual.solid:
                solids.setdefault(visual.body, []).append(visual)
            elif visual.layer == "joint":
                out.append((t, _path_of(key, visual.body), entity_archetypes(visual)))
            else:
                capsule = model.shape.get(visual.body) == "capsule"
                out.append((t, body_path(visual.body), entity_archetypes(visual, capsule)))
        for body, visuals in solids.items():
            merged = EntityVisual(f"solid/{body}", body, tuple(p for v in visuals for p in v.primitives), True)
            out.append((t, body_path(body, "collision"), entity_archetypes(merged)))
    return out


def body_path(body: str, *below: str) -> str:
    """The entity path of a body (or something under it): ``/world/<body>``; names are escaped as Rerun needs."""
    import rerun as rr

    return str(rr.new_entity_path([WORLD, body, *below]))


def _path_of(entity_id: str, body: str = "") -> str:
    kind, _, rest = entity_id.partition("/")
    if kind in ("solid", "collision"):
        return body_path(rest.partition("/")[0] if kind == "solid" else rest, "collision")
    if kind == "joint":
        return body_path(body, "joint", rest)
    return body_path(rest)
