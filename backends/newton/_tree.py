"""The joints of a world as Newton articulations (trees), judged without the engine.

Newton holds joints in articulations: each body the child of one joint at most, every articulation's joints
contiguous, parents before children. Joints are oriented away from the world (static bodies and the
environment are the world) or, in a group of bodies not joined to it, from the group's first body, which
then gets a free joint as its root; a joint whose ``body`` ends up the parent reads its coordinate negated
(sign -1). A loop of joints, a joint on a kinematic body (Newton's kinematic bodies are roots) and a joint
moving a static body are refused (UnsupportedFeature).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, Motion


@dataclass(frozen=True)
class Oriented:
    """One joint of ``world.joints`` as Newton builds it: parent (a world body index, None for the world),
    child, sign of the coordinate."""

    joint: int
    parent: int | None
    child: int
    sign: float


@dataclass(frozen=True)
class Group:
    """One articulation: its root body when it floats (None: rooted in the world), its joints in order."""

    root: int | None
    joints: tuple[Oriented, ...]


def groups(world: CompiledWorld) -> list[Group]:
    """The world's joints as articulations, each in breadth-first order from its root."""
    index = {b.name: i for i, b in enumerate(world.bodies)}
    motion = [b.motion for b in world.bodies]
    root: dict[int | None, int | None] = {None: None}

    def find(node: int | None) -> int | None:
        while root.setdefault(node, node) != node:
            node = root[node]
        return node

    ends: list[tuple[int | None, int]] = []
    for joint in world.joints:
        body = index[joint.body]
        other = None if joint.other is None else index[joint.other]
        for i in (body, other):
            if i is not None and motion[i] is Motion.KINEMATIC:
                raise UnsupportedFeature(
                    f"Backend `newton`: joint `{joint.name}` holds kinematic body `{world.bodies[i].name}`; "
                    "Newton's kinematic bodies are the roots of their articulations, moved only by the runner."
                )
        if motion[body] is Motion.STATIC:
            raise UnsupportedFeature(f"Backend `newton`: joint `{joint.name}` moves static body `{joint.body}`.")
        if other is not None and motion[other] is Motion.STATIC:
            other = None
        a, b = find(body), find(other)
        if a == b:
            raise UnsupportedFeature(
                f"Backend `newton` builds joints as trees (Newton's articulations); joint `{joint.name}` closes a "
                f"loop of joints between `{joint.body}` and `{joint.other or 'the environment'}`."
            )
        if b is None:
            a, b = b, a
        root[b] = a
        ends.append((other, body))
    adjacent: dict[int | None, list[int]] = {}
    for k, (other, body) in enumerate(ends):
        adjacent.setdefault(other, []).append(k)
        adjacent.setdefault(body, []).append(k)
    out: list[Group] = []
    seen: set[int] = set()
    starts: list[int | None] = [None, *sorted(i for i in adjacent if i is not None)]
    for start in starts:
        if start not in adjacent or (start is not None and any(start in (o.parent, o.child) for g in out
                                                               for o in g.joints)):  # fmt: skip
            continue
        order: list[Oriented] = []
        queue = [start]
        for node in queue:  # breadth first; `queue` grows while iterating
            for k in adjacent[node]:
                if k in seen:
                    continue
                seen.add(k)
                other, body = ends[k]
                child = body if node == other else other
                if child is None:  # pragma: no cover - the world is only ever a root
                    raise AssertionError("the world as a child")
                order.append(Oriented(k, node, child, 1.0 if child == body else -1.0))
                queue.append(child)
        if order:
            out.append(Group(start, tuple(order)))
    return out
