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

import numpy as np

from ..types import Contact, new_contact


def group_by_pair(n_bodies: int, first: np.ndarray, second: np.ndarray, depth: np.ndarray,
                  force: np.ndarray) -> list[Contact]:  # fmt: skip
    """One Contact per body pair of the points (``first[i]``, ``second[i]`` in either order), sorted.

    ``depth`` is each point's penetration (>= 0 when touching; NaN is ignored unless all are NaN),
    ``force`` its normal force (NaN when the engine cannot say).
    """
    if len(first) == 0:
        return []
    lo, hi = np.minimum(first, second), np.maximum(first, second)
    key = lo.astype(np.int64) * n_bodies + hi
    order = np.argsort(key, kind="stable")  # a pair's points keep the engine's order
    key, depth, force = key[order], np.asarray(depth, float)[order], np.asarray(force, float)[order]
    start = np.flatnonzero(np.concatenate(([True], key[1:] != key[:-1])))
    count = np.diff(np.append(start, len(key)))
    if np.isnan(depth).any():  # NaN spreads through np.maximum; Python's max() fold skips it
        values = depth.tolist()
        deepest = [max(0.0, *values[s : s + c]) for s, c in zip(start.tolist(), count.tolist(), strict=True)]
    else:
        top = np.maximum.reduceat(depth, start)
        deepest = np.where(top > 0.0, top, 0.0).tolist()
    total = force[start].copy()
    for j in range(1, int(count.max())):  # column by column: each pair's j-th point added to its total
        more = count > j
        total[more] += force[start[more] + j]
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
