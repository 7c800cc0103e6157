"""Which friction DART's solver gets: NsgsFrictionSolver's Coulomb cone, or Dantzig's pyramid where the cone fails."""

from __future__ import annotations

from .._kit.stacks import stack_height
from ..errors import UnsupportedFeature
from ..types import CompiledWorld
from . import _surfaces
from ._options import MAX_CONE_MU, MAX_CONE_STACK


def friction_model(world: CompiledWorld, option: str) -> str:
    """``cone`` or ``pyramid`` for the ``friction`` option: ``auto`` takes the cone where DART can solve it.

    NsgsFrictionSolver fails above :data:`MAX_CONE_MU` (``_options``); a pair with such a mu (or inf) slides
    only under a tangential force 100 times its normal load, where the pyramid's direction hardly matters.
    Nor does it hold a column taller than :data:`MAX_CONE_STACK` (``_options``): ``auto`` then takes the
    pyramid (Dantzig's exact LCP), whose only cost is friction's direction on a floor's diagonal.
    """
    if option == "pyramid":
        return option
    if option == "auto" and stack_height(world) > MAX_CONE_STACK:
        return "pyramid"
    names = [b.name for b in world.bodies]
    for a, b in _surfaces.touching_pairs(world):
        mu = world.surface(names[a], names[b]).mu
        if mu > MAX_CONE_MU:
            if option == "auto":
                return "pyramid"
            raise UnsupportedFeature(
                f"Backend `dart` with `friction: cone` solves friction with DART's NsgsFrictionSolver, which "
                f"fails above mu {MAX_CONE_MU:g} (NaN impulses: bodies fall through); the pair "
                f"`{names[a]}`-`{names[b]}` has mu={mu:g}. Use `friction: pyramid` or a smaller mu."
            )
    return "cone"
