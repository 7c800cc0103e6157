"""Which body pairs MuJoCo lets touch, and ``<exclude>`` for the pairs that never touch (the filtering
described in ``_model``)."""

from __future__ import annotations

from typing import Any

from ..types import CompiledWorld
from . import _native


def touch(a: str, b: str, group: dict[str, str], moving: set[str]) -> bool:
    """Whether MuJoCo's filtering lets bodies ``a`` and ``b`` collide (before excludes): different rigid
    groups (MuJoCo's weld bodies), one of them moving freely (contype bits)."""
    return group[a] != group[b] and bool({group[a], group[b]} & moving)


def excluded(world: CompiledWorld) -> list[tuple[str, str]]:
    """The body pairs that never touch, in order, once each: joined bodies (ODE programs skip connected
    bodies), then ``CompiledWorld.excluded_pairs`` (a model's adjacent links, the scenario's exclusions)."""
    pairs = [(j.body, j.other) for j in world.joints if j.other is not None]
    pairs += list(world.excluded_pairs)
    unique: dict[frozenset[str], tuple[str, str]] = {}
    for a, b in pairs:
        unique.setdefault(frozenset((a, b)), (a, b))
    return list(unique.values())


def add_excludes(
    spec: Any, world: CompiledWorld, group: dict[str, str], moving: set[str], names: _native.Names
) -> None:
    """A MuJoCo ``<exclude>`` (a body pair) for each excluded pair that MuJoCo's filtering would let touch."""
    for a, b in excluded(world):
        if a != b and touch(a, b, group, moving):
            spec.add_exclude(bodyname1=names.body(a), bodyname2=names.body(b))
