"""Contact points grouped into one :class:`~backends.types.Contact` per touching body pair, and the pairs of
several engine steps merged into the scenario step's, written once for every adapter.

Per pair (``a < b``): the number of points, the deepest penetration (0 when no point penetrates) and the
sum of the points' normal forces. Sums are taken point by point in the engine's order, from the first
point (``((f0 + f1) + f2) + ...``), so that a pair's total does not depend on how its points were found
or on numpy's summation strategy.

Over the engine steps of one scenario step (``world.substeps``, or an engine's own extra steps) the pairs
are those touching in **any** of them: ``points`` and ``depth`` are the largest seen and ``normal_force``
is the mean over all the engine steps (a pair absent from one contributes 0 there), i.e. the impulse the
contact transmitted over the step divided by ``dt``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..types import Contact, ContactPoint, new_contact

#: Up to this many points the grouping is a Python loop; beyond it numpy's sort and columns are faster
#: (both give the same numbers: the same sums in the same order, the same depth fold).
NUMPY_FROM = 64


#: A per-point column: a list from Python reads, or an array from numpy ones.
Column = Sequence[Any] | np.ndarray


def group_by_pair(n_bodies: int, first: Column, second: Column, depth: Column, force: Column) -> list[Contact]:
    """One Contact per body pair of the points (``first[i]``, ``second[i]`` in either order), sorted.

    ``depth`` is each point's penetration (>= 0 when touching; NaN is ignored), ``force`` its normal force
    (NaN when the engine cannot say).
    """
    count = len(first)
    if count == 0:
        return []
    if count < NUMPY_FROM:
        return _grouped_in_python(n_bodies, _as_list(first), _as_list(second), _as_list(depth), _as_list(force))
    return _grouped_with_numpy(n_bodies, np.asarray(first), np.asarray(second), np.asarray(depth, float),
                               np.asarray(force, float))  # fmt: skip


def _as_list(values: Column) -> list[Any]:
    return values.tolist() if isinstance(values, np.ndarray) else list(values)


def _grouped_in_python(n: int, first: list[int], second: list[int], depth: list[float],
                       force: list[float]) -> list[Contact]:  # fmt: skip
    rows: dict[int, list[Any]] = {}
    for a, b, d, f in zip(first, second, depth, force, strict=True):
        if a > b:
            a, b = b, a
        row = rows.get(a * n + b)
        if row is None:
            rows[a * n + b] = [int(a), int(b), 1, d if d > 0.0 else 0.0, f]  # NaN and -0.0 fold to 0.0
        else:
            row[2] += 1
            if d > row[3]:
                row[3] = d
            row[4] += f
    return [new_contact((r[0], r[1], r[2], float(r[3]), float(r[4]))) for _, r in sorted(rows.items())]


def _grouped_with_numpy(n_bodies: int, first: np.ndarray, second: np.ndarray, depth: np.ndarray,
                        force: np.ndarray) -> list[Contact]:  # fmt: skip
    lo, hi = np.minimum(first, second), np.maximum(first, second)
    key = lo.astype(np.int64) * n_bodies + hi
    if (key[1:] < key[:-1]).any():  # MuJoCo and others list points pair by pair already: no sort then
        order = np.argsort(key, kind="stable")  # a pair's points keep the engine's order
        key, depth, force = key[order], depth[order], force[order]
    new = np.empty(len(key), dtype=bool)
    new[0] = True
    np.not_equal(key[1:], key[:-1], out=new[1:])
    start = np.flatnonzero(new)
    count = np.diff(np.append(start, len(key)))
    if np.isnan(depth).any():  # NaN spreads through np.maximum; the fold from 0.0 skips it
        values = depth.tolist()
        deepest = [max(0.0, *values[s : s + c]) for s, c in zip(start.tolist(), count.tolist(), strict=True)]
    else:
        top = np.maximum.reduceat(depth, start)
        deepest = np.where(top > 0.0, top, 0.0).tolist()
    # Each pair's forces summed point by point: row j of the table holds every pair's j-th point, -0.0
    # where a pair has fewer (x + -0.0 is x for every x, -0.0, inf and NaN included), rows added in order.
    pair_of = np.cumsum(new) - 1
    table = np.full((int(count.max()), len(start)), -0.0)
    table[np.arange(len(key)) - start[pair_of], pair_of] = force
    total = table[0].copy()
    for row in table[1:]:
        total += row
    pair = key[start]
    rows = zip((pair // n_bodies).tolist(), (pair % n_bodies).tolist(), count.tolist(), deepest, total.tolist(),
               strict=True)  # fmt: skip
    return list(map(new_contact, rows))


def merge_substeps(steps: Sequence[list[Contact]], n: int) -> list[Contact]:
    """The pairs touching in any of ``n`` engine steps (``steps``, each sorted): most points, deepest,
    mean normal force over the ``n`` steps. One engine step: its contacts unchanged."""
    if n == 1 and len(steps) == 1:
        return list(steps[0])
    merged: dict[tuple[int, int], list[float]] = {}
    for contacts in steps:
        for c in contacts:
            row = merged.get((c.a, c.b))
            if row is None:
                merged[(c.a, c.b)] = [c.points, c.depth, c.normal_force]
            else:
                row[0] = max(row[0], c.points)
                row[1] = max(row[1], c.depth)
                row[2] += c.normal_force
    return [
        new_contact((a, b, int(row[0]), float(row[1]), float(row[2]) / n)) for (a, b), row in sorted(merged.items())
    ]


class SubstepContacts:
    """Collects the grouped contacts of each engine step of a scenario step, then merges them."""

    def __init__(self, engine_steps: int) -> None:
        self.engine_steps = engine_steps
        self._steps: list[list[Contact]] = []

    def start(self) -> None:
        self._steps = []

    def add(self, contacts: list[Contact]) -> None:
        self._steps.append(contacts)

    def merged(self, last: list[Contact] | None = None) -> list[Contact]:
        """The step's contacts; ``last``: the final engine step's, when the adapter groups it only now."""
        steps = self._steps if last is None else [*self._steps, last]
        return merge_substeps(steps, self.engine_steps) if steps else []


def contact_point(i: int, j: int, pos: Any, normal: Any, depth: float, force: float) -> ContactPoint:
    """A point between bodies ``i`` and ``j`` whose ``normal`` points from ``i`` to ``j``, as the contract
    lists it: ``a < b``, the normal turned round when ``i > j``; plain floats."""
    x, y, z = (float(v) for v in normal)
    if i > j:
        i, j, x, y, z = j, i, -x, -y, -z
    px, py, pz = (float(v) for v in pos)
    return ContactPoint(int(i), int(j), (px, py, pz), (x, y, z), float(depth), float(force))


def sorted_points(points: list[ContactPoint]) -> list[ContactPoint]:
    """Sorted by (a, b), a pair's points kept in the engine's order."""
    return sorted(points, key=_pair_key)


def _pair_key(point: ContactPoint) -> tuple[int, int]:
    return point.a, point.b
