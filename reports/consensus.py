"""Where no truth is known, the engines judged by each other: pairwise deviations, groups and a majority.

Two engines *agree* on a quantity while their deviation from each other stays within its threshold. A
pair that has once gone beyond it no longer agrees, so agreement only breaks as time goes on and the run
splits into phases at the pairs' first times over. In each phase the engines are grouped: first the
largest set whose members all agree pairwise (ties by name), then the largest among the rest, and so on.

A *majority* is a group of more than half of the engines compared that no other set of the same size
could replace (two overlapping sets of agreeing engines, e.g. a ~ b, b ~ c but a !~ c: no majority). The
engines outside a majority *depart*: each is named once, with the time it left (the phase's start) and
its largest distance from the majority's members while that majority lasts (``until``: the time it
broke up, or None). Without a majority nobody is named and the groups are
what the report shows: no engine is marked only because it disagrees with one other engine (with two
engines that disagree there is never a majority).

Each engine's series (for the charts and the per-run statistics) is its largest distance, at each time,
from the engines it is judged with: the final majority's members (itself excluded), else those of the
last majority there was, else every other engine.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from itertools import combinations
from typing import Any

import numpy as np

from reports import divergence as dv

__all__ = ["Judgement", "Pair", "judge"]

#: (times in s, deviation between the two engines at those times)
Pair = tuple[np.ndarray, np.ndarray]


@dataclass
class Judgement:
    """What :func:`judge` found for one quantity (all lists in report order: the engines' given order)."""

    engines: list[str]
    pairs: list[dict[str, Any]]  # {a, b, max, max_time, rms, first_over}
    phases: list[dict[str, Any]]  # {from, groups, majority}: from None is the run's start
    departures: list[dict[str, Any]]  # {backend, from, until, majority, max, max_time}
    series: dict[str, Pair] = field(default_factory=dict)  # engine -> its deviation from those it is judged with

    @property
    def groups(self) -> list[list[str]]:
        return self.phases[-1]["groups"] if self.phases else []

    @property
    def majority(self) -> list[str] | None:
        return self.phases[-1]["majority"] if self.phases else None

    @property
    def no_majority_from(self) -> float | None:
        """The start of the first phase without a majority (None: there always was one)."""
        return next((p["from"] for p in self.phases if p["majority"] is None), None)

    def to_json(self) -> dict[str, Any]:
        return {"engines": self.engines, "groups": self.groups, "majority": self.majority,
                "departures": self.departures, "no_majority_from": self.no_majority_from,
                "phases": self.phases, "pairs": self.pairs}  # fmt: skip


def _key(a: str, b: str, order: dict[str, int]) -> tuple[str, str]:
    return (a, b) if order[a] <= order[b] else (b, a)


def _groups(names: Sequence[str], agree: Callable[[str, str], bool]) -> list[list[str]]:
    left, out = list(names), []
    while left:
        best = next(list(c) for k in range(len(left), 0, -1) for c in combinations(left, k)
                    if all(agree(a, b) for a, b in combinations(c, 2)))  # fmt: skip
        out.append(best)
        left = [n for n in left if n not in best]
    return out


def _majority(names: Sequence[str], groups: list[list[str]], agree: Callable[[str, str], bool]) -> list[str] | None:
    first = groups[0]
    if 2 * len(first) <= len(names):
        return None
    for other in combinations(names, len(first)):
        if set(other) != set(first) and all(agree(a, b) for a, b in combinations(other, 2)):
            return None  # another set as large agrees too: which one is the majority is not decided
    return first


def _spread(engine: str, others: Sequence[str], pairs: Mapping[tuple[str, str], Pair],
            order: dict[str, int]) -> Pair:  # fmt: skip
    """At each time any pair covers, the largest deviation of ``engine`` from ``others`` (NaN: none)."""
    found = [pairs[_key(engine, o, order)] for o in others if _key(engine, o, order) in pairs]
    found = [(np.asarray(t, float), np.asarray(e, float)) for t, e in found if len(t)]
    if not found:
        return np.zeros(0), np.zeros(0)
    ns = [np.rint(t * 1e9).astype(np.int64) for t, _ in found]
    union = np.unique(np.concatenate(ns))
    table = np.full((len(found), union.size), np.nan)
    for row, (n, (_, e)) in enumerate(zip(ns, found, strict=True)):
        table[row, np.searchsorted(union, n)] = e
    ok = np.isfinite(table).any(axis=0)
    worst = np.full(union.size, np.nan)
    worst[ok] = np.nanmax(table[:, ok], axis=0)
    return union / 1e9, worst


def _r(x: float | None) -> float | None:
    return None if x is None else round(float(x), 9)


def judge(engines: Sequence[str], pairs: Mapping[tuple[str, str], Pair], threshold: float) -> Judgement:
    """Judge ``engines`` on one quantity from their pairwise deviations (``pairs[(a, b)]`` with ``a`` before
    ``b`` in ``engines``; a missing pair was not comparable and counts as agreeing)."""
    names = list(engines)
    order = {n: i for i, n in enumerate(names)}
    first_over: dict[tuple[str, str], float | None] = {}
    rows = []
    for a, b in combinations(names, 2):
        if (a, b) not in pairs:
            continue
        t, e = pairs[(a, b)]
        s = dv.stats(np.asarray(t, float), np.asarray(e, float), threshold)
        first_over[(a, b)] = s["first_over"]
        rows.append({"a": a, "b": b, **{k: _r(s[k]) for k in ("max", "max_time", "rms", "first_over")}})
    breaks = sorted({t for t in first_over.values() if t is not None})
    phases: list[dict[str, Any]] = []
    for start in [None, *breaks]:
        def agree(a: str, b: str, start: float | None = start) -> bool:
            t = first_over.get(_key(a, b, order))
            return t is None or start is None or t > start

        groups = _groups(names, agree)
        if phases and phases[-1]["groups"] == groups:
            continue
        phases.append({"from": _r(start), "groups": groups, "majority": _majority(names, groups, agree)})
    departures: list[dict[str, Any]] = []
    named: set[str] = set()
    for i, phase in enumerate(phases):
        majority = phase["majority"]
        if majority is None:
            continue
        until = next((p["from"] for p in phases[i + 1 :] if p["majority"] != majority), None)
        for engine in names:
            if engine in majority or engine in named:
                continue
            named.add(engine)
            t, e = _spread(engine, majority, pairs, order)
            held = t < until - 1e-9 if until is not None else np.ones(t.size, bool)
            s = dv.stats(t[held], e[held], threshold)
            departures.append({"backend": engine, "from": phase["from"], "until": until, "majority": majority,
                               "max": _r(s["max"]), "max_time": _r(s["max_time"])})  # fmt: skip
    last = next((p["majority"] for p in reversed(phases) if p["majority"] is not None), None)
    series = {n: _spread(n, [m for m in (last or names) if m != n] or [m for m in names if m != n], pairs, order)
              for n in names}  # fmt: skip
    return Judgement(names, rows, phases, departures, series)
