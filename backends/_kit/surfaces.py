"""Per-body contact coefficients that give every pair that can touch its scenario surface, for engines that
carry friction and restitution per body (or per shape) and combine two of them by a rule (:class:`Blend`)
instead of taking a value per pair as ODE does.

Two solvers, as the engines need them: :func:`solve_min` and :func:`solve_product` find exact values (DART:
friction the minimum, restitution the product of coefficients in [0, 1]); :func:`fit_product` fits a product
in log space by least squares and :func:`check_fit` refuses a pair it misses (PyBullet: both products, friction
clamped). A pair that cannot be given its value is refused up front (UnsupportedFeature naming the pair and the
rule). Nothing here imports an engine.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, Surface

_LOG_TOL = 1e-9


class Blend(str, enum.Enum):
    """How an engine combines the two bodies' coefficients of a contact."""

    PRODUCT = "product"  # c_a * c_b: PyBullet's friction and restitution, DART's restitution
    MIN = "min"  # min(c_a, c_b): DART's friction

    def combine(self, a: float, b: float) -> float:
        return a * b if self is Blend.PRODUCT else min(a, b)


def pair_surfaces(world: CompiledWorld, pairs: Sequence[tuple[int, int]]) -> list[Surface]:
    """``world.surface`` of each body index pair."""
    names = [b.name for b in world.bodies]
    return [world.surface(names[i], names[j]) for i, j in pairs]


def pair_text(names: Sequence[str], a: int, b: int) -> str:
    return f"`{names[a]}`-`{names[b]}`"


# --- exact solutions (min; product with every coefficient in [0, 1]) ------------------------------------


def solve_min(
    n: int, target: dict[tuple[int, int], float], names: Sequence[str], backend: str, carriers: str = "bodies"
) -> tuple[float, ...]:
    """min(f[a], f[b]) == target for every pair (friction ``mu``): the smallest candidate is f[i] = the largest
    of its pairs' values."""
    f = [1.0] * n
    seen = [False] * n
    for (a, b), value in target.items():
        for i in (a, b):
            f[i] = value if not seen[i] else max(f[i], value)
            seen[i] = True
    for (a, b), value in target.items():
        if min(f[a], f[b]) != value:
            raise UnsupportedFeature(
                f"Backend `{backend}` combines friction as the minimum of the two {carriers}' coefficients, so "
                f"the pair {pair_text(names, a, b)} cannot get mu={value:g} together with the other pairs "
                f"(it would get {min(f[a], f[b]):g})."
            )
    return tuple(f)


def solve_product(
    n: int, target: dict[tuple[int, int], float], names: Sequence[str], backend: str, carriers: str = "bodies"
) -> tuple[float, ...]:
    """r[a] * r[b] == target for every pair (restitution ``bounce``) with every r in [0, 1], solved in log
    space one connected component at a time."""
    r = [0.0] * n
    positive = {p: e for p, e in target.items() if e > 0.0}
    forced = {i for p in positive for i in p}
    for (a, b), e in target.items():
        if e > 1.0:
            raise UnsupportedFeature(
                f"Backend `{backend}` needs restitution in [0, 1]; pair {pair_text(names, a, b)} asks for {e:g}."
            )
        if e == 0.0 and a in forced and b in forced:
            raise UnsupportedFeature(
                f"Backend `{backend}` combines restitution as the product of the two {carriers}' coefficients, "
                f"so the pair {pair_text(names, a, b)} cannot get bounce 0 while both bodies bounce in "
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
        for i, x in _solve_component(start, adjacency, names, backend, carriers).items():
            r[i] = math.exp(x)
            done.add(i)
    return tuple(r)


def _solve_component(
    start: int,
    adjacency: dict[int, list[tuple[int, float, tuple[int, int]]]],
    names: Sequence[str],
    backend: str,
    carriers: str,
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
                f"Backend `{backend}` combines restitution as the product of the two {carriers}' coefficients; "
                f"no per-body values give the pair {pair_text(names, *pair)} its bounce together with the "
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
            f"Backend `{backend}` combines restitution as the product of the two {carriers}' coefficients, "
            f"each at most 1; the pair {pair_text(names, *pair)} cannot get its bounce together with the "
            f"other pairs of `{names[worst]}`."
        )
    return {i: min(0.0, c[i] + s[i] * t_fixed) for i in order}


Adjacency = dict[int, list[tuple[int, float, tuple[int, int]]]]


def solve_sums(
    start: int,
    adjacency: Adjacency,
    names: Sequence[str],
    hi: float,
    tol: float,
    refuse: Callable[[tuple[int, int], str], UnsupportedFeature],
) -> dict[int, float]:
    """x[a] + x[b] == t for every pair (a, b, t) of the connected component of ``start``, every x in [0, hi]:
    x[i] = c[i] + s[i]*t (s = +-1), t fixed by an odd cycle or chosen in the middle of the interval that keeps
    every x in bounds (Drake's harmonic mean as sums of reciprocals, Newton's mean). ``refuse(pair, why)``: the
    error naming the pair that cannot get its value."""
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
        scale = tol * max(1.0, abs(t))
        if coef == 0:
            if abs(rest) > scale:
                raise refuse(pair, "together with the other pairs of its bodies (a cycle of pairs)")
            continue
        value = rest / coef
        if fixed is not None and abs(value - fixed) > scale:
            raise refuse(pair, "together with the other pairs of its bodies (a cycle of pairs)")
        fixed = value if fixed is None else fixed
    lo_t = max(max((-base[i] for i in order if sign[i] > 0), default=-math.inf),
               max((base[i] - hi for i in order if sign[i] < 0), default=-math.inf))  # fmt: skip
    hi_t = min(min((hi - base[i] for i in order if sign[i] > 0), default=math.inf),
               min((base[i] for i in order if sign[i] < 0), default=math.inf))  # fmt: skip
    if fixed is None:
        fixed = 0.5 * (lo_t + hi_t) if math.isfinite(lo_t + hi_t) else (lo_t if math.isfinite(lo_t) else hi_t)
    if fixed < lo_t - tol or fixed > hi_t + tol:
        worst = min(order, key=lambda i: min(base[i] + sign[i] * fixed, hi - base[i] - sign[i] * fixed))
        raise refuse(adjacency[worst][0][2], f"together with the other pairs of `{names[worst]}`")
    return {i: min(hi, max(0.0, base[i] + sign[i] * fixed)) for i in order}


def solve_exact(
    blend: Blend,
    n: int,
    target: dict[tuple[int, int], float],
    names: Sequence[str],
    backend: str,
    carriers: str = "bodies",
) -> tuple[float, ...]:
    """Per-body values that ``blend`` combines into each pair's target exactly (:func:`solve_min`,
    :func:`solve_product`)."""
    solver = solve_min if blend is Blend.MIN else solve_product
    return solver(n, target, names, backend, carriers)


# --- a least-squares fit of a product, checked pair by pair ----------------------------------------------


def fit_product(n: int, pairs: Sequence[tuple[int, int]], targets: Sequence[float], fallback: float) -> np.ndarray:
    """Per-body c >= 0 with c_i * c_j ~= target for each pair (zeros exactly; untouched bodies sqrt(fallback))."""
    coeff = np.full(n, math.sqrt(fallback))
    touched = np.zeros(n, dtype=bool)
    nonzero_pair = np.zeros(n, dtype=bool)
    for (i, j), t in zip(pairs, targets, strict=True):
        touched[i] = touched[j] = True
        if t > 0.0:
            nonzero_pair[i] = nonzero_pair[j] = True
    zero_body = touched & ~nonzero_pair  # every pair of this body asks for 0
    coeff[zero_body] = 0.0
    rows = [(i, j, t) for (i, j), t in zip(pairs, targets, strict=True) if t > 0.0]
    if rows:
        a = np.zeros((len(rows), n))
        b = np.empty(len(rows))
        for r, (i, j, t) in enumerate(rows):
            a[r, i] = a[r, j] = 1.0
            b[r] = math.log(t)
        solved = np.linalg.lstsq(a, b, rcond=None)[0]
        used = a.any(axis=0)
        coeff[used] = np.exp(solved[used])
    return coeff


def check_fit(
    world: CompiledWorld,
    pairs: Sequence[tuple[int, int]],
    targets: Sequence[float],
    coeff: np.ndarray,
    what: str,
    *,
    backend: str,
    engine: str,
    tolerance: float,
    combined: Callable[[float], float] = lambda x: x,
) -> None:
    """Refuse the first pair whose combined coefficient ``combined(c_i * c_j)`` misses its target by more than
    ``tolerance`` (relative), or is not 0 where 0 is asked."""
    for (i, j), t in zip(pairs, targets, strict=True):
        got = combined(coeff[i] * coeff[j])
        if abs(got - t) > tolerance * t or (t == 0.0 and got != 0.0):
            a, b = world.bodies[i].name, world.bodies[j].name
            raise UnsupportedFeature(
                f"Backend `{backend}` cannot give bodies `{a}` and `{b}` {what} {t:g}: {engine} combines "
                f"per-body coefficients as a product and the scenario's pair surfaces have no common "
                f"solution (best fit {got:.4g}, more than {tolerance:.0%} off). Use another "
                f"backend or make the pair values consistent (products of per-body values)."
            )
