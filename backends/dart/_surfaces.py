"""Per-shape friction and restitution that reproduce every pair's surface under DART's combining rules.

DART has no per-pair contact parameters: each shape carries a friction coefficient and a restitution
coefficient, and a contact combines them as ``min(fa, fb)`` and ``ra * rb`` (dart/constraint/
ContactSurface.cpp). Restitution must stay in [0, 1] and friction finite, or DART falls back to its
defaults with a warning at every contact. This module finds per-body values that give every pair that
can touch (at least one dynamic body, not joined by a joint) exactly the world's surface, or raises
:class:`UnsupportedFeature` naming a pair that cannot be matched. It does not import the engine.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, Motion

#: The finite friction coefficient that stands for ``mu = inf`` (DART rejects inf). Coulomb friction
#: with a coefficient of 1e6 never slips in any scenario this tool runs; the value is raised above the
#: world's largest finite mu so that the order of the pairs is kept.
MU_INF = 1.0e6
_LOG_TOL = 1e-9


@dataclass(frozen=True)
class ShapeCoefficients:
    friction: tuple[float, ...]  # per body, in CompiledWorld.bodies order
    restitution: tuple[float, ...]


def touching_pairs(world: CompiledWorld) -> list[tuple[int, int]]:
    """Body pairs whose contacts matter: at least one dynamic body, and not joined by a joint."""
    joined = {frozenset((j.body, j.other)) for j in world.joints if j.other is not None}
    pairs = []
    bodies = world.bodies
    for a in range(len(bodies)):
        for b in range(a + 1, len(bodies)):
            if Motion.DYNAMIC not in (bodies[a].motion, bodies[b].motion):
                continue
            if frozenset((bodies[a].name, bodies[b].name)) in joined:
                continue
            pairs.append((a, b))
    return pairs


def finite_mu(world: CompiledWorld) -> float:
    """The stand-in for an infinite mu in ``world``."""
    finite = [world.default_surface.mu] + [p.surface.mu for p in world.pair_surfaces]
    largest = max((m for m in finite if math.isfinite(m)), default=0.0)
    return max(MU_INF, 10.0 * largest)


def solve(
    world: CompiledWorld,
    pairs: Iterable[tuple[int, int]] | None = None,
    plastic: frozenset[tuple[int, int]] = frozenset(),
) -> ShapeCoefficients:
    """Per-body (friction, restitution) matching ``pairs`` (default: every pair that can touch); the pairs
    in ``plastic`` (approaching below their ``bounce_vel`` this step) get bounce 0.

    Raises UnsupportedFeature when DART's combining rules cannot give all of them their surface.
    """
    pairs = touching_pairs(world) if pairs is None else list(pairs)
    names = [b.name for b in world.bodies]
    inf_mu = finite_mu(world)
    mu: dict[tuple[int, int], float] = {}
    bounce: dict[tuple[int, int], float] = {}
    for a, b in pairs:
        surface = world.surface(names[a], names[b])
        mu[(a, b)] = surface.mu if math.isfinite(surface.mu) else inf_mu
        bounce[(a, b)] = 0.0 if (a, b) in plastic else surface.bounce
    return ShapeCoefficients(
        friction=_solve_min(len(names), mu, names),
        restitution=_solve_product(len(names), bounce, names),
    )


def thresholded_pairs(world: CompiledWorld) -> dict[tuple[int, int], float]:
    """Pairs that can touch, bounce and have a ``bounce_vel`` > 0: pair -> bounce_vel."""
    names = [b.name for b in world.bodies]
    out: dict[tuple[int, int], float] = {}
    for a, b in touching_pairs(world):
        surface = world.surface(names[a], names[b])
        if surface.bounce > 0.0 and surface.bounce_vel > 0.0:
            out[(a, b)] = surface.bounce_vel
    return out


def _pair_text(names: Sequence[str], a: int, b: int) -> str:
    return f"`{names[a]}`-`{names[b]}`"


def _solve_min(n: int, target: dict[tuple[int, int], float], names: Sequence[str]) -> tuple[float, ...]:
    """min(f[a], f[b]) == target for every pair: the smallest candidate is f[i] = max of its pairs."""
    f = [1.0] * n
    seen = [False] * n
    for (a, b), value in target.items():
        for i in (a, b):
            f[i] = value if not seen[i] else max(f[i], value)
            seen[i] = True
    for (a, b), value in target.items():
        if min(f[a], f[b]) != value:
            raise UnsupportedFeature(
                f"Backend `dart` combines friction as the minimum of the two shapes' coefficients, so the "
                f"pair {_pair_text(names, a, b)} cannot get mu={value:g} together with the other pairs "
                f"(it would get {min(f[a], f[b]):g})."
            )
    return tuple(f)


def _solve_product(n: int, target: dict[tuple[int, int], float], names: Sequence[str]) -> tuple[float, ...]:
    """r[a] * r[b] == target for every pair with every r in [0, 1], solved in log space."""
    r = [0.0] * n
    positive = {p: e for p, e in target.items() if e > 0.0}
    forced = {i for p in positive for i in p}
    for (a, b), e in target.items():
        if e > 1.0:
            raise UnsupportedFeature(
                f"Backend `dart` needs restitution in [0, 1]; pair {_pair_text(names, a, b)} asks for {e:g}."
            )
        if e == 0.0 and a in forced and b in forced:
            raise UnsupportedFeature(
                f"Backend `dart` combines restitution as the product of the two shapes' coefficients, so "
                f"the pair {_pair_text(names, a, b)} cannot get bounce 0 while both bodies bounce in "
                f"other pairs."
            )
    adjacency: dict[int, list[tuple[int, float, tuple[int, int]]]] = {i: [] for i in forced}
    for (a, b), e in positive.items():
        adjacency[a].append((b, math.log(e), (a, b)))
        adjacency[b].append((a, math.log(e), (a, b)))
    done: set[int] = set()
    for start in sorted(forced):
        if start in done:
            continue
        for i, x in _solve_component(start, adjacency, names).items():
            r[i] = math.exp(x)
            done.add(i)
    return tuple(r)


def _solve_component(
    start: int, adjacency: dict[int, list[tuple[int, float, tuple[int, int]]]], names: Sequence[str]
) -> dict[int, float]:
    """x[a] + x[b] == log(e_ab) on one connected component, x <= 0; x[i] = c[i] + s[i]*t."""
    c, s = {start: 0.0}, {start: 1}
    order, t_fixed = [start], None
    edges: list[tuple[int, int, float, tuple[int, int]]] = []
    for u in order:  # breadth first; `order` grows while iterating
        for v, log_e, pair in adjacency[u]:
            edges.append((u, v, log_e, pair))
            if v not in c:
                c[v], s[v] = log_e - c[u], -s[u]
                order.append(v)
    for u, v, log_e, pair in edges:
        coef, rest = s[u] + s[v], log_e - c[u] - c[v]
        if coef == 0:
            ok = abs(rest) <= _LOG_TOL
        else:
            t = rest / coef
            ok = t_fixed is None or abs(t - t_fixed) <= _LOG_TOL
            t_fixed = t if t_fixed is None else t_fixed
        if not ok:
            raise UnsupportedFeature(
                f"Backend `dart` combines restitution as the product of the two shapes' coefficients; no "
                f"per-body values give the pair {_pair_text(names, *pair)} its bounce together with the "
                f"other pairs of its bodies."
            )
    lo = max((c[i] for i in order if s[i] < 0), default=-math.inf)  # x[i] = c[i] - t <= 0
    hi = min((-c[i] for i in order if s[i] > 0), default=math.inf)  # x[i] = c[i] + t <= 0
    if t_fixed is None:
        t_fixed = 0.5 * (lo + hi)  # both bounds are finite: a component has both parities
    if t_fixed < lo - _LOG_TOL or t_fixed > hi + _LOG_TOL:
        worst = max(order, key=lambda i: c[i] + s[i] * t_fixed)
        pair = adjacency[worst][0][2]
        raise UnsupportedFeature(
            f"Backend `dart` combines restitution as the product of the two shapes' coefficients, each "
            f"at most 1; the pair {_pair_text(names, *pair)} cannot get its bounce together with the "
            f"other pairs of `{names[worst]}`."
        )
    return {i: min(0.0, c[i] + s[i] * t_fixed) for i in order}
