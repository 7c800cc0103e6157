"""Events across runs: each run's timeline, and how it matches the reference's.

Occurrences of an event are matched with the reference's occurrences of the same event in time order,
each at most once and only within :data:`MATCH_WINDOW` seconds, choosing the matching that minimises
the sum of |time differences| plus :data:`MATCH_WINDOW` per unmatched occurrence (a small dynamic
programme), so an extra bounce early in one engine does not shift every later pairing. Unmatched run
occurrences are *extra*, unmatched reference occurrences *missing*. The difference in first occurrence
is run minus reference (seconds).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from reports.runs import Run

__all__ = ["MATCH_WINDOW", "compare_events", "event_times", "match_times"]

#: seconds: occurrences further apart than this are not the same occurrence
MATCH_WINDOW = 0.5


def _r(x: float) -> float:
    return round(float(x), 9)


def event_times(run: Run) -> dict[str, list[float]]:
    """Event name -> its times in ``run``, names in order of first occurrence."""
    out: dict[str, list[float]] = {}
    for e in run.trace.events if run.trace is not None else []:
        out.setdefault(e.name, []).append(_r(e.t))
    return out


def match_times(mine: list[float], theirs: list[float], window: float = MATCH_WINDOW) -> list[tuple[int, int]]:
    """Index pairs (mine, theirs), in time order, of the cheapest order-preserving matching."""
    n, m = len(mine), len(theirs)
    cost = [[0.0] * (m + 1) for _ in range(n + 1)]
    for i in range(1, n + 1):
        cost[i][0] = i * window
    for j in range(1, m + 1):
        cost[0][j] = j * window
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            best = min(cost[i - 1][j], cost[i][j - 1]) + window
            d = abs(mine[i - 1] - theirs[j - 1])
            if d <= window:
                best = min(best, cost[i - 1][j - 1] + d)
            cost[i][j] = best
    pairs = []
    i, j = n, m
    while i > 0 and j > 0:
        d = abs(mine[i - 1] - theirs[j - 1])
        if d <= window and cost[i][j] == cost[i - 1][j - 1] + d:
            pairs.append((i - 1, j - 1))
            i, j = i - 1, j - 1
        elif cost[i][j] == cost[i - 1][j] + window:
            i -= 1
        else:
            j -= 1
    return pairs[::-1]


def _status(count: int, ref_count: int, unmatched: bool) -> str:
    if not unmatched:
        return "match"
    if count == 0:
        return "missing"
    if ref_count == 0:
        return "extra"
    if count == ref_count:
        return "differs"
    return "fewer" if count < ref_count else "more"


def compare_events(runs: Sequence[Run], reference: str) -> dict[str, Any]:
    """``names`` (reference's order first), per-run timelines, and per-run comparisons with the reference."""
    times = {r.backend: event_times(r) for r in runs}
    ref_times = times.get(reference, {})
    names = list(ref_times)
    for per_run in times.values():
        names += [n for n in per_run if n not in names]
    timelines = {
        r.backend: [{"t": _r(e.t), "name": e.name, "source": e.source} for e in r.trace.events]
        if r.trace is not None
        else []
        for r in runs
    }
    comparison: dict[str, list[dict[str, Any]]] = {}
    has_reference = any(r.backend == reference and r.trace is not None for r in runs)
    for run in runs:
        if run.backend == reference or not has_reference:
            continue
        rows = []
        for name in names:
            mine, theirs = times[run.backend].get(name, []), ref_times.get(name, [])
            if not mine and not theirs:
                continue
            pairs = match_times(mine, theirs)
            matched_mine, matched_theirs = {i for i, _ in pairs}, {j for _, j in pairs}
            extra = [t for i, t in enumerate(mine) if i not in matched_mine]
            missing = [t for j, t in enumerate(theirs) if j not in matched_theirs]
            rows.append(
                {
                    "name": name,
                    "count": len(mine),
                    "reference_count": len(theirs),
                    "status": _status(len(mine), len(theirs), bool(extra or missing)),
                    "first": mine[0] if mine else None,
                    "reference_first": theirs[0] if theirs else None,
                    "first_delta": _r(mine[0] - theirs[0]) if mine and theirs else None,
                    "matched": [[theirs[j], _r(mine[i] - theirs[j])] for i, j in pairs],
                    "extra": extra,
                    "missing": missing,
                }
            )
        comparison[run.backend] = rows
    return {"names": names, "timelines": timelines, "comparison": comparison}
