"""Panda3D-style collision solids and CollisionHandlerEvent in/again/out events.

Solids are tested by overlap at the recorded state (no sweep: Panda3D's default, notes §5). A from-sphere
hits an into-sphere when the centres are within the summed radii, an into-polygon when it lies within its
radius of the polygon's plane (either side) and its circle on the plane reaches the polygon, an into-box
when the box's closest point is within the radius. One entry per (from, into) node pair; events come in
pair-sort order: in (new pair), again (still colliding), out (no longer colliding).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from runner.compile.solids import NodeDef, SolidDef
from runner.language.patterns import expand


@dataclass(frozen=True)
class Pose:
    """A node's pose for the collision traverser: position, rotation matrix and scale."""

    pos: np.ndarray  # (3,)
    rot: np.ndarray  # (3, 3)
    scale: float


def _world_sphere(s: SolidDef, pose: Pose) -> tuple[np.ndarray, float]:
    return pose.pos + pose.scale * (pose.rot @ s.center), s.radius * pose.scale


def _point_in_polygon(p: np.ndarray, pts: np.ndarray, normal: np.ndarray) -> bool:
    n = len(pts)
    for i in range(n):
        edge = pts[(i + 1) % n] - pts[i]
        if np.dot(np.cross(edge, p - pts[i]), normal) < 0.0:
            return False
    return True


def _dist_to_polygon_edges(p: np.ndarray, pts: np.ndarray) -> float:
    best = np.inf
    n = len(pts)
    for i in range(n):
        a, b = pts[i], pts[(i + 1) % n]
        ab = b - a
        t = np.clip(np.dot(p - a, ab) / max(np.dot(ab, ab), 1e-300), 0.0, 1.0)
        best = min(best, float(np.linalg.norm(p - (a + t * ab))))
    return best


def sphere_hits(center: np.ndarray, radius: float, into: SolidDef, pose: Pose) -> bool:
    if into.kind == "sphere":
        c2, r2 = _world_sphere(into, pose)
        return float(np.dot(center - c2, center - c2)) <= (radius + r2) ** 2
    if into.kind == "polygon":
        pts = pose.pos + pose.scale * (into.vertices @ pose.rot.T)
        normal = np.zeros(3)
        for i in range(len(pts)):
            normal += np.cross(pts[i], pts[(i + 1) % len(pts)])
        normal /= np.linalg.norm(normal)
        dist = float(np.dot(center - pts[0], normal))
        if abs(dist) > radius:
            return False
        projected = center - dist * normal
        if _point_in_polygon(projected, pts, normal):
            return True
        return bool(_dist_to_polygon_edges(projected, pts) <= np.sqrt(max(radius * radius - dist * dist, 0.0)))
    # box: closest point of the oriented box to the sphere's centre
    box_center = pose.pos + pose.scale * (pose.rot @ into.center)
    local = pose.rot.T @ (center - box_center)
    half = (into.half if into.half is not None else np.zeros(3)) * pose.scale
    closest = np.clip(local, -half, half)
    return float(np.dot(local - closest, local - closest)) <= radius * radius


def nodes_collide(from_node: NodeDef, from_pose: Pose, into_node: NodeDef, into_pose: Pose) -> bool:
    for solid in from_node.solids:
        center, radius = _world_sphere(solid, from_pose)
        if any(sphere_hits(center, radius, into, into_pose) for into in into_node.solids):
            return True
    return False


@dataclass(frozen=True)
class CollisionEvent:
    """A collision event to deliver: its kind (in, again, out), name and the two nodes."""

    kind: str  # in | again | out
    name: str  # the event name after pattern expansion
    from_name: str
    into_name: str


class EventHandler:
    """CollisionHandlerEvent: compares this traversal's pairs with the last one's."""

    def __init__(self, in_patterns: Sequence[str], again_patterns: Sequence[str], out_patterns: Sequence[str]) -> None:
        self.patterns = {"in": tuple(in_patterns), "again": tuple(again_patterns), "out": tuple(out_patterns)}
        self.last: set[tuple[str, str, bool]] = set()

    def update(self, current: Iterable[tuple[str, str, bool]]) -> list[CollisionEvent]:
        """``current``: (from name, into name, into is physics geometry) of every colliding pair now."""
        now = set(current)
        events: list[CollisionEvent] = []
        for pair in sorted(now | self.last):
            kind = "again" if (pair in now and pair in self.last) else ("in" if pair in now else "out")
            for pattern in self.patterns[kind]:
                name = expand(pattern, pair[0], pair[1], pair[2])
                if name:
                    events.append(CollisionEvent(kind, name, pair[0], pair[1]))
        self.last = now
        return events


def _bounding_radius(s: SolidDef) -> float:
    """Radius about ``s.center`` of a sphere holding the solid (unscaled)."""
    if s.kind == "sphere":
        return s.radius
    if s.kind == "box" and s.half is not None:
        return float(np.linalg.norm(s.half))
    if s.vertices is not None:
        return float(np.max(np.linalg.norm(s.vertices - s.center, axis=1)))
    return 0.0


def overlapping_spheres(
    c_from: np.ndarray, r_from: np.ndarray, c_all: np.ndarray, r_all: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i, j) where sphere i of the first set overlaps sphere j of the second (touching counts).

    A sweep along x in numpy: the spheres of the second set sorted by their lowest x; each sphere of the
    first set is tested only against those whose x extent can reach it. No Python loop over pairs.
    """
    if not len(c_from) or not len(c_all):
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    lo = c_all[:, 0] - r_all
    order = np.argsort(lo, kind="stable")
    lo_sorted = lo[order]
    widest = 2.0 * float(r_all.max())
    start = np.searchsorted(lo_sorted, c_from[:, 0] - r_from - widest, "left")
    stop = np.searchsorted(lo_sorted, c_from[:, 0] + r_from, "right")
    counts = stop - start
    i = np.repeat(np.arange(len(c_from)), counts)
    offsets = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    j = order[np.repeat(start, counts) + offsets]
    d = c_from[i] - c_all[j]
    keep = np.einsum("ij,ij->i", d, d) <= (r_from[i] + r_all[j]) ** 2
    return i[keep], j[keep]


class SolidTraverser:
    """The collision traverser for solids: which (from node, into node) pairs overlap now.

    A broad phase finds the node pairs whose solids' bounding spheres overlap (vectorised, see
    :func:`overlapping_spheres`); only those get the exact tests of :func:`nodes_collide`. The work in
    Python grows with the number of near pairs, not with colliders x nodes.
    """

    #: Bounding spheres are inflated by this (relative, plus as much in metres) so that rounding in the
    #: broad phase never drops a pair the exact test would report.
    SLACK = 1e-9

    def __init__(self, nodes: Sequence[NodeDef], colliders: Sequence[str]) -> None:
        self.nodes = {n.name: n for n in nodes}
        self.colliders = [self.nodes[c] for c in colliders]
        order = list(self.nodes.values())
        self._order = order
        rank = {n.name: k for k, n in enumerate(order)}
        solids = [(k, n.body, s) for k, n in enumerate(order) for s in n.solids]
        self._node = np.array([k for k, _, _ in solids], dtype=np.int64)
        self._body = np.array([b for _, b, _ in solids], dtype=np.int64)
        self._center = np.array([s.center for _, _, s in solids], dtype=float).reshape(len(solids), 3)
        self._radius = np.array([_bounding_radius(s) for _, _, s in solids], dtype=float)
        self._collider_rank: dict[int, int] = {}
        for position, c in enumerate(self.colliders):
            self._collider_rank.setdefault(rank[c.name], position)
        colliding = np.zeros(len(order), dtype=bool)  # by node rank (np.isin would import numpy.ma at start-up)
        colliding[list(self._collider_rank)] = True
        self._from = np.flatnonzero(colliding[self._node])

    def traverse(self, poses: Sequence[Pose]) -> list[tuple[str, str, bool]]:
        pos = np.array([p.pos for p in poses], dtype=float).reshape(len(poses), 3)
        rot = np.array([p.rot for p in poses], dtype=float).reshape(len(poses), 3, 3)
        scale = np.array([p.scale for p in poses], dtype=float)
        return self.traverse_arrays(pos, rot, scale)

    def traverse_arrays(self, pos: np.ndarray, rot: np.ndarray, scale: np.ndarray) -> list[tuple[str, str, bool]]:
        """Bodies' positions (N, 3), rotation matrices (N, 3, 3) and scales (N,), in world order."""
        if not self.colliders or not self._from.size:
            return []
        b = self._body
        centers = pos[b] + scale[b, None] * np.einsum("sij,sj->si", rot[b], self._center)
        radii = self._radius * scale[b] * (1.0 + self.SLACK) + self.SLACK
        i, j = overlapping_spheres(centers[self._from], radii[self._from], centers, radii)
        f_node, i_node = self._node[self._from[i]], self._node[j]
        keep = f_node != i_node
        codes = np.unique(f_node[keep] * len(self._order) + i_node[keep])
        candidates = sorted((self._collider_rank[int(c) // len(self._order)], int(c) % len(self._order)) for c in codes)
        hits = []
        for position, into_rank in candidates:
            f, into = self.colliders[position], self._order[into_rank]
            if nodes_collide(f, _pose(pos, rot, scale, f.body), into, _pose(pos, rot, scale, into.body)):
                hits.append((f.name, into.name, False))
        return hits


def _pose(pos: np.ndarray, rot: np.ndarray, scale: np.ndarray, body: int) -> Pose:
    return Pose(pos[body], rot[body], float(scale[body]))


def quat_matrices(q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) (w, x, y, z) quaternions."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    out = np.empty((len(q), 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    out[:, 2, 0], out[:, 2, 1], out[:, 2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    return out


def quat_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a (w, x, y, z) quaternion."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
