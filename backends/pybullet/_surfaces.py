"""Per-body restitution and friction that give every body pair the scenario's surface on PyBullet.

PyBullet has no per-pair surface: it combines the two bodies' coefficients as a product
(restitution rA*rB; lateral friction fA*fB, clamped to 10 in ``calculateCombinedFriction``). So each
body gets a coefficient ``c`` such that ``c_a * c_b`` equals the pair's value: ``sqrt(value)`` when
every pair shares the default, otherwise a least-squares fit in log space (``backends._kit.surfaces``),
checked to 1 % per pair.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .._kit.pairs import touching_pairs
from .._kit.surfaces import Blend, check_fit, fit_product, pair_surfaces
from ..types import CompiledWorld

#: Bullet's MAX_FRICTION: the combined friction never exceeds this (btManifoldResult.cpp).
FRICTION_CLAMP = 10.0
#: Bullet's combining rules (btManifoldResult.cpp): both products
FRICTION_BLEND = RESTITUTION_BLEND = Blend.PRODUCT
#: A pair whose combined coefficient misses the target by more than this (relative) is refused.
MATCH_TOLERANCE = 0.01


@dataclass(frozen=True)
class SurfaceFit:
    restitution: tuple[float, ...]  # per body, world.bodies order
    friction: tuple[float, ...]
    restitution_threshold: float  # global restitutionVelocityThreshold (ODE bounce_vel)
    threshold_note: str  # non-empty when pairs asked for different bounce_vel values
    method: str  # "sqrt" (one surface for all pairs) or "least-squares"


def fit_surfaces(world: CompiledWorld) -> SurfaceFit:
    """Per-body coefficients for every pair that can touch (``backends._kit.pairs``): ``world.surface(a, b)``."""
    n = len(world.bodies)
    pairs = touching_pairs(world)
    surfaces = pair_surfaces(world, pairs)
    bounce = [max(s.bounce, 0.0) for s in surfaces]
    mu = [min(max(s.mu, 0.0), FRICTION_CLAMP) for s in surfaces]  # mu >= 10 (inf too): Bullet's clamp
    default = world.default_surface
    if not world.pair_surfaces or not pairs:
        rest = np.full(n, math.sqrt(max(default.bounce, 0.0)))
        fric = np.full(n, math.sqrt(min(max(default.mu, 0.0), FRICTION_CLAMP)))
        method = "sqrt"
    else:
        rest = fit_product(n, pairs, bounce, max(default.bounce, 0.0))
        fric = fit_product(n, pairs, mu, min(max(default.mu, 0.0), FRICTION_CLAMP))
        method = "least-squares"
    check = functools.partial(check_fit, world, pairs, backend="pybullet", engine="PyBullet", tolerance=MATCH_TOLERANCE)
    check(bounce, rest, "restitution")
    check(mu, fric, "friction", combined=lambda x: min(x, FRICTION_CLAMP))
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
