"""Per-body friction coefficients that give every pair its ``mu`` under Drake's combination rule.

Drake has no per-pair contact parameters: each geometry carries one ``CoulombFriction`` and a contact uses
the harmonic mean ``2*ma*mb / (ma + mb)`` of its two geometries' coefficients (drake
multibody/plant/coulomb_friction.h). In reciprocals that rule is linear: ``1/ma + 1/mb = 2/mu``, so
per-body values exist exactly when that linear system over the pairs that can touch has a solution with
every reciprocal >= 0 (0 standing for ``mu = inf``). This module solves it per connected component of the
pair graph (one free parameter on a component without an odd cycle, none with one) and raises
:class:`UnsupportedFeature` naming the pair it cannot give its ``mu``. It imports no engine.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from .._kit.surfaces import Adjacency, solve_sums
from ..errors import UnsupportedFeature
from ..types import CompiledWorld, Motion

#: The finite coefficient that stands for ``mu = inf`` (CoulombFriction needs a finite value). A pair whose
#: other body carries a finite ``mu`` gets it to within ``mu / (2 * MU_INF)`` relative (1e-7 for mu 0.2).
MU_INF = 1.0e6
_TOL = 1e-12


def touching_pairs(world: CompiledWorld) -> list[tuple[int, int]]:
    """Body pairs whose contacts exist: at least one dynamic body, not joined by a joint, not excluded."""
    joined = {frozenset((j.body, j.other)) for j in world.joints if j.other is not None}
    joined |= {frozenset(p) for p in world.excluded_pairs}
    bodies = world.bodies
    return [
        (a, b)
        for a in range(len(bodies))
        for b in range(a + 1, len(bodies))
        if Motion.DYNAMIC in (bodies[a].motion, bodies[b].motion)
        and frozenset((bodies[a].name, bodies[b].name)) not in joined
    ]


def solve(world: CompiledWorld) -> tuple[float, ...]:
    """One friction coefficient per body (``world.bodies`` order) whose harmonic means give every pair that
    can touch its ``mu`` (``inf`` as :data:`MU_INF`); bodies in no such pair get the default surface's."""
    names = [b.name for b in world.bodies]
    target: dict[tuple[int, int], float] = {}
    for a, b in touching_pairs(world):
        mu = world.surface(names[a], names[b]).mu
        target[(a, b)] = 0.0 if math.isinf(mu) else (math.inf if mu == 0.0 else 2.0 / mu)
    recip = _solve_sums(len(names), target, names)
    default = world.default_surface.mu
    out = []
    for i in range(len(names)):
        r = recip.get(i)
        if r is None:
            out.append(_coefficient(0.0 if math.isinf(default) else 1.0 / default if default > 0 else math.inf))
        else:
            out.append(_coefficient(r))
    return tuple(out)


def _coefficient(recip: float) -> float:
    if math.isinf(recip):
        return 0.0
    return MU_INF if recip <= 1.0 / MU_INF else 1.0 / recip


def _pair(names: Sequence[str], a: int, b: int) -> str:
    return f"`{names[a]}`-`{names[b]}`"


def _refuse(names: Sequence[str], pair: tuple[int, int], why: str) -> UnsupportedFeature:
    return UnsupportedFeature(
        f"Backend `drake` gives each geometry one friction coefficient and a contact their harmonic mean "
        f"2*ma*mb/(ma+mb) (no per-pair friction): the pair {_pair(names, *pair)} cannot get its `mu` {why}. "
        f"Backends with per-pair surfaces: mujoco, ode, pybullet."
    )


def _solve_sums(n: int, target: dict[tuple[int, int], float], names: Sequence[str]) -> dict[int, float]:
    """x[a] + x[b] == target[(a, b)] with every x >= 0 (inf: mu 0, that body slides on everything)."""
    x: dict[int, float] = {}
    zero_mu = {p for p, t in target.items() if math.isinf(t)}
    for a, b in zero_mu:  # mu 0 on a pair: one of its bodies must carry mu 0, so every pair of it has mu 0
        for i in (a, b):
            if all(math.isinf(t) for p, t in target.items() if i in p):
                x[i] = math.inf
                break
        else:
            raise _refuse(names, (a, b), "of 0 together with the other pairs of its bodies")
    finite = {p: t for p, t in target.items() if p[0] not in x and p[1] not in x}
    adjacency: dict[int, list[tuple[int, float, tuple[int, int]]]] = {}
    for (a, b), t in finite.items():
        adjacency.setdefault(a, []).append((b, t, (a, b)))
        adjacency.setdefault(b, []).append((a, t, (a, b)))
    for start in sorted(adjacency):
        if start not in x:
            x.update(_component(start, adjacency, names))
    return x


def _component(start: int, adjacency: Adjacency, names: Sequence[str]) -> dict[int, float]:
    """One connected component of the reciprocals' sums, every reciprocal >= 0 (``_kit.surfaces.solve_sums``)."""
    return solve_sums(start, adjacency, names, math.inf, _TOL, lambda pair, why: _refuse(names, pair, why))
