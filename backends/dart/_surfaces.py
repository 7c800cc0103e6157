"""Per-shape friction and restitution that reproduce every pair's surface under DART's combining rules.

DART has no per-pair contact parameters: each shape carries a friction coefficient and a restitution
coefficient, and a contact combines them as ``min(fa, fb)`` and ``ra * rb`` (dart/constraint/
ContactSurface.cpp). Restitution must stay in [0, 1] and friction finite, or DART falls back to its
defaults with a warning at every contact. The kit's exact solvers (``backends._kit.surfaces``: ``Blend.MIN``
and ``Blend.PRODUCT``) find per-body values that give every pair that can touch (``backends._kit.pairs``)
exactly the world's surface, or raise :class:`UnsupportedFeature` naming a pair that cannot be matched. It
does not import the engine.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from .._kit.pairs import touching_pairs
from .._kit.surfaces import Blend, solve_exact
from ..types import CompiledWorld

#: The finite friction coefficient that stands for ``mu = inf`` (DART rejects inf). Coulomb friction
#: with a coefficient of 1e6 never slips in any scenario this tool runs; the value is raised above the
#: world's largest finite mu so that the order of the pairs is kept.
MU_INF = 1.0e6
#: DART's combining rules (ContactSurface.cpp)
FRICTION_BLEND, RESTITUTION_BLEND = Blend.MIN, Blend.PRODUCT

__all__ = [
    "FRICTION_BLEND",
    "MU_INF",
    "RESTITUTION_BLEND",
    "ShapeCoefficients",
    "finite_mu",
    "solve",
    "thresholded_pairs",
    "touching_pairs",
]


@dataclass(frozen=True)
class ShapeCoefficients:
    friction: tuple[float, ...]  # per body, in CompiledWorld.bodies order
    restitution: tuple[float, ...]


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
        friction=solve_exact(FRICTION_BLEND, len(names), mu, names, "dart", carriers="shapes"),
        restitution=solve_exact(RESTITUTION_BLEND, len(names), bounce, names, "dart", carriers="shapes"),
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
