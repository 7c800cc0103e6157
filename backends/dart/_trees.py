"""Skeleton trees for DART: which body is each skeleton's root, and which joint links each child.

DART simulates joints in reduced coordinates, so every connected group of bodies becomes one Skeleton
whose joints form a tree. A group is anchored to the world by at most one of: a static body (welded),
a joint to the environment, or a kinematic body (driven). A world joint whose direction is opposite to
the tree's (the joint's ``body`` is the tree parent) is kept with ``sign = -1``: its coordinate, rate,
motor and stops are negated, since the motion of ``other`` relative to ``body`` is the reverse one.
Closed loops are refused with :class:`UnsupportedFeature`. This module does not import the engine.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, JointSpec, Motion


@dataclass(frozen=True)
class Link:
    parent: int  # body index of the tree parent
    child: int  # body index of the tree child
    joint: int  # joint index in CompiledWorld.joints
    sign: float  # +1: the world joint's body is the child; -1: it is the parent


@dataclass(frozen=True)
class Tree:
    root: int  # body index
    root_joint: int | None  # a joint to the environment, else None (free, welded or kinematic root)
    links: tuple[Link, ...]  # in breadth-first order: a parent always comes before its children

    @property
    def bodies(self) -> tuple[int, ...]:
        return (self.root, *(link.child for link in self.links))


def plan(world: CompiledWorld) -> list[Tree]:
    """One tree per connected group of bodies, in the order of each group's first body."""
    index = {b.name: i for i, b in enumerate(world.bodies)}
    env_joint: dict[int, int] = {}
    edges: dict[int, list[tuple[int, int]]] = {i: [] for i in range(len(world.bodies))}
    for j, spec in enumerate(world.joints):
        body = index[spec.body]
        if spec.other is None:
            if body in env_joint:
                _loop(world, spec, "a second joint to the environment")
            env_joint[body] = j
        else:
            other = index[spec.other]
            if other == body:
                raise UnsupportedFeature(f"Joint `{spec.name}` joins body `{spec.body}` to itself.")
            edges[body].append((other, j))
            edges[other].append((body, j))
    trees: list[Tree] = []
    seen: set[int] = set()
    for first in range(len(world.bodies)):
        if first in seen:
            continue
        group = _group(first, edges)
        seen.update(group)
        trees.append(_tree(world, group, edges, env_joint))
    return trees


def _group(first: int, edges: dict[int, list[tuple[int, int]]]) -> list[int]:
    group, todo = [first], [first]
    found = {first}
    while todo:
        for other, _ in edges[todo.pop()]:
            if other not in found:
                found.add(other)
                group.append(other)
                todo.append(other)
    return sorted(group)


def _tree(
    world: CompiledWorld, group: list[int], edges: dict[int, list[tuple[int, int]]], env_joint: dict[int, int]
) -> Tree:
    bodies = world.bodies
    anchors = [i for i in group if i in env_joint or bodies[i].motion is not Motion.DYNAMIC]
    joints = sorted({j for i in group for _, j in edges[i]})
    if len(anchors) > 1 or (anchors and bodies[anchors[0]].motion is not Motion.DYNAMIC and anchors[0] in env_joint):
        names = ", ".join(f"`{bodies[i].name}`" for i in anchors)
        raise UnsupportedFeature(
            f"Backend `dart` builds jointed bodies as trees in reduced coordinates; the group of bodies "
            f"joined to {names} is anchored more than once (static, kinematic or joined to the "
            f"environment), which closes a loop."
        )
    if len(joints) != len(group) - 1:
        _loop(world, world.joints[joints[-1]], "a closed loop of joints")
    root = anchors[0] if anchors else group[0]
    links: list[Link] = []
    order, placed = [root], {root}
    for parent in order:  # breadth first; `order` grows while iterating
        for child, j in sorted(edges[parent], key=lambda e: e[1]):
            if child in placed:
                continue
            placed.add(child)
            order.append(child)
            spec = world.joints[j]
            links.append(Link(parent, child, j, 1.0 if spec.body == bodies[child].name else -1.0))
    return Tree(root, env_joint.get(root), tuple(links))


def _loop(world: CompiledWorld, spec: JointSpec, what: str) -> None:
    raise UnsupportedFeature(
        f"Backend `dart` builds jointed bodies as trees in reduced coordinates; joint `{spec.name}` of "
        f"scenario `{world.name}` makes {what}, which it cannot simulate."
    )
