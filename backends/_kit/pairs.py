"""Which body pairs can touch: the pairs whose contact parameters an adapter must get right.

A pair can touch when at least one of its bodies is dynamic (static and kinematic bodies never touch each
other, backends/base.py), the two are not joined directly by a joint (ODE's joined bodies do not collide, and
neither do an articulation's parent and child links), and the world does not exclude it
(``CompiledWorld.excluded_pairs``, ``collision:exclude-pairs``). Nothing here imports an engine.
"""

from __future__ import annotations

from ..types import CompiledWorld, Motion


def _ordered(index: dict[str, int], a: str, b: str) -> tuple[int, int]:
    i, j = index[a], index[b]
    return (i, j) if i < j else (j, i)


def joined_pairs(world: CompiledWorld) -> set[tuple[int, int]]:
    """Body index pairs (i < j) joined directly by a joint."""
    index = {b.name: i for i, b in enumerate(world.bodies)}
    return {_ordered(index, j.body, j.other) for j in world.joints if j.other is not None}


def excluded_index_pairs(world: CompiledWorld) -> set[tuple[int, int]]:
    """``world.excluded_pairs`` as body index pairs (i < j)."""
    index = {b.name: i for i, b in enumerate(world.bodies)}
    return {_ordered(index, a, b) for a, b in world.excluded_pairs}


def touching_pairs(world: CompiledWorld) -> list[tuple[int, int]]:
    """Body index pairs (i < j) that can touch, in index order."""
    moving = [b.motion is Motion.DYNAMIC for b in world.bodies]
    never = joined_pairs(world) | excluded_index_pairs(world)
    n = len(moving)
    return [(i, j) for i in range(n) for j in range(i + 1, n) if (moving[i] or moving[j]) and (i, j) not in never]
