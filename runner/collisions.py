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

from .scenario.patterns import expand


@dataclass(frozen=True)
class SolidDef:
    """A solid in its body's frame, unscaled (the body's current scale is applied at test time)."""

    kind: str  # sphere | polygon | box
    center: np.ndarray  # (3,)
    radius: float = 0.0
    half: np.ndarray | None = None  # box half sizes
    vertices: np.ndarray | None = None  # (n, 3) polygon


@dataclass(frozen=True)
class NodeDef:
    name: str
    body: int  # index into the world's bodies
    solids: tuple[SolidDef, ...]


@dataclass(frozen=True)
class Pose:
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
    half = into.half * pose.scale
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


class SolidTraverser:
    """The collision traverser for solids: which (from node, into node) pairs overlap now."""

    def __init__(self, nodes: Sequence[NodeDef], colliders: Sequence[str]) -> None:
        self.nodes = {n.name: n for n in nodes}
        self.colliders = [self.nodes[c] for c in colliders]

    def traverse(self, poses: Sequence[Pose]) -> list[tuple[str, str, bool]]:
        hits = []
        for f in self.colliders:
            for into in self.nodes.values():
                if into.name != f.name and nodes_collide(f, poses[f.body], into, poses[into.body]):
                    hits.append((f.name, into.name, False))
        return hits


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
