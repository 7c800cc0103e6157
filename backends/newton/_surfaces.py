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
    adjacency: dict[int, list[tuple[int, float, tuple[int, int]]]],
    names: Sequence[str],
    what: str,
    hi: float,
    declared: Declared,
) -> dict[int, float]:
    base, sign, order = {start: 0.0}, {start: 1}, [start]
    edges = []
    for u in order:  # breadth first; `order` grows while iterating
        for v, t, pair in adjacency[u]:
            edges.append((u, v, t, pair))
            if v not in base:
                base[v], sign[v] = t - base[u], -sign[u]
                order.append(v)
    fixed: float | None = None
    for u, v, t, pair in edges:
        coef, rest = sign[u] + sign[v], t - base[u] - base[v]
        scale = _TOL * max(1.0, abs(t))
        if coef == 0:
            if abs(rest) > scale:
                raise _refuse(
                    names, declared, pair, what, "together with the other pairs of its bodies (a cycle of pairs)"
                )
            continue
        value = rest / coef
        if fixed is not None and abs(value - fixed) > scale:
            raise _refuse(names, declared, pair, what, "together with the other pairs of its bodies (a cycle of pairs)")
        fixed = value if fixed is None else fixed
    # c_i = base_i + sign_i * t within [0, hi]
    lo_t = max(max((-base[i] for i in order if sign[i] > 0), default=-math.inf),
               max((base[i] - hi for i in order if sign[i] < 0), default=-math.inf))  # fmt: skip
    hi_t = min(min((hi - base[i] for i in order if sign[i] > 0), default=math.inf),
               min((base[i] for i in order if sign[i] < 0), default=math.inf))  # fmt: skip
    if fixed is None:
        fixed = 0.5 * (lo_t + hi_t) if math.isfinite(lo_t + hi_t) else (lo_t if math.isfinite(lo_t) else hi_t)
    if fixed < lo_t - _TOL or fixed > hi_t + _TOL:
        worst = min(order, key=lambda i: min(base[i] + sign[i] * fixed, hi - base[i] - sign[i] * fixed))
        raise _refuse(
            names, declared, adjacency[worst][0][2], what, f"together with the other pairs of `{names[worst]}`"
        )
    return {i: min(hi, max(0.0, base[i] + sign[i] * fixed)) for i in order}
