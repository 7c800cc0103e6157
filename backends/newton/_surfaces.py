"""Per-body friction and restitution that give every pair that can touch its scenario surface under Newton's
rule: a contact takes the arithmetic **mean** of its two shapes' ``mu`` and ``restitution`` (newton
solvers/xpbd/kernels.py, ``mu /= mat_nonzero``; the same in the semi-implicit contact kernels Featherstone
uses). Every shape of a body carries the body's values.

The mean is linear, ``c_a + c_b = 2 * target``, so per-body values exist exactly when that system over the
pairs that can touch (``backends._kit.pairs.touching_pairs``) has a solution within the coefficient's bounds.
It is solved one connected component of the pair graph at a time: ``c_i = base_i + sign_i * t`` with one free
``t``, fixed by an odd cycle or chosen in the middle of the interval that keeps every value in bounds. A pair
that cannot get its value is refused up front (UnsupportedFeature naming it). Nothing here imports an engine.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from .._kit.pairs import touching_pairs
from .._kit.surfaces import Adjacency, solve_sums
from ..errors import UnsupportedFeature
from ..types import CompiledWorld

#: The finite coefficient that stands for ``mu = inf`` (a float32 engine needs a finite value): a contact
#: then holds until its tangential force exceeds 1e5 times its normal force.
MU_INF = 1.0e5
_TOL = 1e-9
#: the body name pairs of the scenario's `pairs` entries, in the order written (for messages)
Declared = frozenset[tuple[str, str]]


@dataclass(frozen=True)
class BodySurfaces:
    """One friction coefficient and one restitution per body (``world.bodies`` order)."""

    mu: tuple[float, ...]
    restitution: tuple[float, ...]


def solve(world: CompiledWorld) -> BodySurfaces:
    """Per-body ``mu`` and ``restitution`` whose means give every pair that can touch its surface."""
    names = [b.name for b in world.bodies]
    pairs = touching_pairs(world)
    surfaces = [world.surface(names[a], names[b]) for a, b in pairs]
    mu_target = {p: 2.0 * (MU_INF if math.isinf(s.mu) else s.mu) for p, s in zip(pairs, surfaces, strict=True)}
    e_target = {p: 2.0 * s.bounce for p, s in zip(pairs, surfaces, strict=True)}
    default = world.default_surface
    declared = frozenset((p.a, p.b) for p in world.pair_surfaces)
    mu = solve_means(len(names), mu_target, names, "friction `mu`", hi=math.inf,
                     fallback=MU_INF if math.isinf(default.mu) else default.mu, declared=declared)  # fmt: skip
    e = solve_means(len(names), e_target, names, "restitution `bounce`", hi=1.0, fallback=default.bounce,
                    declared=declared)  # fmt: skip
    return BodySurfaces(mu, e)


def solve_means(
    n: int,
    target: dict[tuple[int, int], float],
    names: Sequence[str],
    what: str,
    *,
    hi: float,
    fallback: float,
    declared: Declared = frozenset(),
) -> tuple[float, ...]:
    """c[a] + c[b] == target[(a, b)] with 0 <= c <= hi; bodies in no pair get ``fallback``."""
    adjacency: dict[int, list[tuple[int, float, tuple[int, int]]]] = {}
    for (a, b), t in target.items():
        adjacency.setdefault(a, []).append((b, t, (a, b)))
        adjacency.setdefault(b, []).append((a, t, (a, b)))
    out = [fallback] * n
    done: set[int] = set()
    for start in sorted(adjacency):
        if start in done:
            continue
        for i, value in _component(start, adjacency, names, what, hi, declared).items():
            out[i] = value
            done.add(i)
    return tuple(out)


def _refuse(names: Sequence[str], declared: Declared, pair: tuple[int, int], what: str, why: str) -> UnsupportedFeature:
    a, b = (names[i] for i in pair)
    if (b, a) in declared:  # as the scenario's `pairs` entry names it
        a, b = b, a
    return UnsupportedFeature(
        f"Backend `newton` gives each shape one {what} and a contact the mean of its two shapes' values (no "
        f"per-pair surfaces): the pair `{a}`-`{b}` cannot get its value {why}. Backends with per-pair surfaces: "
        f"mujoco, ode, pybullet."
    )


def _component(
    start: int,
    adjacency: Adjacency,
    names: Sequence[str],
    what: str,
    hi: float,
    declared: Declared,
) -> dict[int, float]:
    return solve_sums(start, adjacency, names, hi, _TOL, lambda pair, why: _refuse(names, declared, pair, what, why))
