"""Per-body restitution and friction that give every body pair the scenario's surface on PyBullet.

PyBullet has no per-pair surface: it combines the two bodies' coefficients as a product
(restitution rA*rB; lateral friction fA*fB, clamped to 10 in ``calculateCombinedFriction``). So each
body gets a coefficient ``c`` such that ``c_a * c_b`` equals the pair's value: ``sqrt(value)`` when
every pair shares the default, otherwise a least-squares fit in log space, checked to 1 % per pair.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, Motion, Surface

#: Bullet's MAX_FRICTION: the combined friction never exceeds this (btManifoldResult.cpp).
FRICTION_CLAMP = 10.0
#: A pair whose combined coefficient misses the target by more than this (relative) is refused.
MATCH_TOLERANCE = 0.01


@dataclass(frozen=True)
class SurfaceFit:
    restitution: tuple[float, ...]  # per body, world.bodies order
    friction: tuple[float, ...]
    restitution_threshold: float  # global restitutionVelocityThreshold (ODE bounce_vel)
    threshold_note: str  # non-empty when pairs asked for different bounce_vel values
    method: str  # "sqrt" (one surface for all pairs) or "least-squares"


def collidable_pairs(world: CompiledWorld, excluded: set[tuple[int, int]]) -> list[tuple[int, int]]:
    """Body pairs (i < j) that can touch: at least one dynamic body, not joined directly."""
    moving = [b.motion is Motion.DYNAMIC for b in world.bodies]
    n = len(world.bodies)
    return [
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if (moving[i] or moving[j]) and (i, j) not in excluded
    ]


def _fit(
    n: int,
    pairs: Sequence[tuple[int, int]],
    targets: Sequence[float],
    fallback: float,
) -> np.ndarray:
    """Per-body c >= 0 with c_i * c_j ~= target for each pair (zeros handled exactly)."""
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


def _check(
    world: CompiledWorld,
    pairs: Sequence[tuple[int, int]],
    targets: Sequence[float],
    coeff: np.ndarray,
    what: str,
    clamp: float,
) -> None:
    for (i, j), t in zip(pairs, targets, strict=True):
        got = min(coeff[i] * coeff[j], clamp)
        if abs(got - t) > MATCH_TOLERANCE * t or (t == 0.0 and got != 0.0):
            a, b = world.bodies[i].name, world.bodies[j].name
            raise UnsupportedFeature(
                f"Backend `pybullet` cannot give bodies `{a}` and `{b}` {what} {t:g}: PyBullet combines "
                f"per-body coefficients as a product and the scenario's pair surfaces have no common "
                f"solution (best fit {got:.4g}, more than {MATCH_TOLERANCE:.0%} off). Use another "
                f"backend or make the pair values consistent (products of per-body values)."
            )


def fit_surfaces(world: CompiledWorld, excluded: set[tuple[int, int]]) -> SurfaceFit:
    """Per-body coefficients for every collidable pair's ``world.surface(a, b)``."""
    n = len(world.bodies)
    pairs = collidable_pairs(world, excluded)
    names = [b.name for b in world.bodies]
    surfaces: list[Surface] = [world.surface(names[i], names[j]) for i, j in pairs]

    def targets(value: Callable[[Surface], float]) -> list[float]:
        return [value(s) for s in surfaces]

    bounce = targets(lambda s: max(s.bounce, 0.0))
    mu = targets(lambda s: min(max(s.mu, 0.0), FRICTION_CLAMP))  # mu >= 10 (inf too): Bullet's clamp
    default = world.default_surface
    if not world.pair_surfaces or not pairs:
        rest = np.full(n, math.sqrt(max(default.bounce, 0.0)))
        fric = np.full(n, math.sqrt(min(max(default.mu, 0.0), FRICTION_CLAMP)))
        method = "sqrt"
    else:
        rest = _fit(n, pairs, bounce, max(default.bounce, 0.0))
        fric = _fit(n, pairs, mu, min(max(default.mu, 0.0), FRICTION_CLAMP))
        method = "least-squares"
    _check(world, pairs, bounce, rest, "restitution", math.inf)
    _check(world, pairs, mu, fric, "friction", FRICTION_CLAMP)
    # ODE's bounce_vel is per contact; Bullet's threshold is global: the smallest among bouncing pairs.
    thresholds = sorted({max(s.bounce_vel, 0.0) for s in surfaces or [default] if s.bounce > 0.0})
    threshold = thresholds[0] if thresholds else max(default.bounce_vel, 0.0)
    note = ""
    if len(thresholds) > 1:
        note = (
            f"pairs ask for bounce_vel {', '.join(f'{t:g}' for t in thresholds)}; PyBullet has one global "
            f"restitutionVelocityThreshold, set to the smallest ({threshold:g})"
        )
    return SurfaceFit(tuple(rest.tolist()), tuple(fric.tolist()), threshold, note, method)
