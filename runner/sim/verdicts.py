"""Verdicts, and the assertions decided at the end of a run from its events and sounds.

A **known limit** (an assertion's ``known_limits`` entry for the backend that runs it) is an expected
failure: the check runs at the default tolerance, and :func:`apply_known_limit` turns its outcome round.
A failure becomes a verdict that does not fail the run (status ``known limit``, with the measured figure
and the cause in its message); a pass fails the run, because the entry is no longer needed. Every
execution path (run, batch, sweep, pytest, Ray, conformance) gets the same verdicts, hence the same exit
code; only the rendering differs (JUnit ``skipped``, pytest ``xfail``, reports and the trace say "known
limit").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from runner.language import model_assertions as A
from runner.language.expressions import fmt

TIME_EPS = 1e-9

PASSED, FAILED, KNOWN_LIMIT = "passed", "failed", "known limit"


@dataclass
class Verdict:
    """One assertion's verdict: passed or not, measured against expected, when, and why."""

    name: str
    kind: str
    passed: bool  # the verdict does not fail the run (a known limit's expected failure does not)
    measured: str
    expected: str
    time: float | None = None  # when it was decided (first failure, first success, or the sample time)
    message: str = ""
    #: the numbers behind a numeric verdict, unformatted (None where the check is not numeric)
    value: float | None = None
    target: float | None = None
    tolerance: float | None = None
    #: the backend's known limit for this assertion (measured, cause, doc), when it has one
    known_limit: dict[str, Any] | None = None

    @property
    def status(self) -> str:
        """``passed``, ``failed``, or ``known limit`` (an expected failure that does not fail the run)."""
        if self.known_limit is not None and self.passed:
            return KNOWN_LIMIT
        return PASSED if self.passed else FAILED

    @property
    def deviation(self) -> float | None:
        """|value - target| of a numeric check, None otherwise."""
        if self.value is None or self.target is None or not math.isfinite(self.value - self.target):
            return None
        return abs(self.value - self.target)

    def as_dict(self) -> dict[str, Any]:
        limit = {"known_limit": dict(self.known_limit)} if self.known_limit is not None else {}
        return {
            "name": self.name,
            "kind": self.kind,
            "passed": self.passed,
            "measured": self.measured,
            "expected": self.expected,
            "time": self.time,
            "message": self.message,
            "value": _finite(self.value),
            "target": _finite(self.target),
            "tolerance": _finite(self.tolerance),
            **limit,  # only on a known limit's verdict: every other verdict (and trace) is as before
        }


def apply_known_limit(v: Verdict, limits: Mapping[str, Any], backend: str) -> Verdict:
    """The verdict of an assertion with ``known_limits`` on ``backend`` (unchanged if it has none there).

    A check that fails as its case file says passes as ``known limit``; one that passes fails: the entry is
    no longer needed."""
    limit = limits.get(backend)
    if limit is None:
        return v
    entry = limit.model_dump() if hasattr(limit, "model_dump") else dict(limit)
    shown = fmt(v.deviation) if v.deviation is not None else v.measured
    if v.passed:
        message = f"known limit no longer needed: {v.name} on {backend} now passes; remove it"
        return replace(v, passed=False, message=message, known_limit=entry)
    message = (
        f"known limit on {backend}: measured {shown} (documented {fmt(entry['measured'])}); {entry['cause']}"
        f" ({entry['doc']})" + (f"; {v.message}" if v.message else "")
    )
    return replace(v, passed=True, message=message, known_limit=entry)


def _finite(x: float | None) -> float | None:
    return x if x is not None and math.isfinite(x) else None


def tolerance(tol: Any, backend: str) -> Any:
    """The tolerance for ``backend``: a number, or an expression's text (evaluated by the caller)."""
    if isinstance(tol, dict):
        return tol.get(backend, tol.get("default", 0.0))
    return tol


def _count_range(count: int | A.CountRange) -> tuple[int, int | None]:
    return (count, count) if isinstance(count, int) else (count.min, count.max)


def _range_text(lo: int, hi: int | None) -> str:
    return f"count {lo}" if lo == hi else f"count in [{lo}, {hi if hi is not None else '∞'}]"


def event_verdict(s: A.EventAssertion, events: Sequence[tuple[float, str]], tol: Callable[[], float]) -> Verdict:
    times = [t for t, name in events if name == s.event]
    first = times[0] if times else None
    problems, measured, expected = [], [f"count {len(times)}", f"first {fmt(first)}"], []
    numbers: tuple[float | None, float | None, float | None] = (None, None, None)
    if isinstance(s.count, int):
        numbers = (float(len(times)), float(s.count), 0.0)
    if s.count is not None:
        lo, hi = _count_range(s.count)
        expected.append(_range_text(lo, hi))
        if len(times) < lo or (hi is not None and len(times) > hi):
            problems.append(f"happened {len(times)} times")
    if s.first is not None:
        within = tol()
        first_at = math.inf if s.first == "end" else float(s.first)
        expected.append(f"first {fmt(first_at)} ± {fmt(within)}")
        numbers = (first, first_at, within)
        if first is None or abs(first - first_at) > within + TIME_EPS:
            problems.append("first time off" if first is not None else "never happened")
    for field_name, other in (("before", s.before), ("after", s.after)):
        if other is None:
            continue
        other_times = [t for t, name in events if name == other]
        expected.append(f"{field_name} {other}")
        if first is None or not other_times:
            problems.append(f"{'it' if first is None else other} never happened")
        elif (first >= other_times[0]) if field_name == "before" else (first <= other_times[0]):
            problems.append(f"first at {fmt(first)}, {other} first at {fmt(other_times[0])}")
    value, target, tolerance_ = numbers
    return Verdict(s.name, "event", not problems, ", ".join(measured), ", ".join(expected), first,
                   "; ".join(problems), value=value, target=target, tolerance=tolerance_)  # fmt: skip


def plays(
    sound: str, starts: Sequence[tuple[float, str]], stops: Sequence[tuple[float, str]]
) -> list[tuple[float, float | None]]:
    """(start, stop) of each play of ``sound``, in order; stop None if it was still playing at the end."""
    started = [t for t, name in starts if name == sound]
    stopped = sorted(t for t, name in stops if name == sound)
    out: list[tuple[float, float | None]] = []
    for i, start in enumerate(started):
        following = started[i + 1] if i + 1 < len(started) else math.inf
        stop = next((t for t in stopped if start - TIME_EPS <= t <= following + TIME_EPS), None)
        if stop is not None:
            stopped.remove(stop)
        out.append((start, stop))
    return out


def sound_verdict(
    s: A.SoundAssertion,
    starts: Sequence[tuple[float, str]],
    stops: Sequence[tuple[float, str]],
    tol: Callable[[], float],
    t_end: float,
) -> Verdict:
    played = plays(s.sound, starts, stops)
    times = [start for start, _ in played]
    problems, expected = [], []
    numbers: tuple[float | None, float | None, float | None] = (None, None, None)
    if isinstance(s.count, int):
        numbers = (float(len(times)), float(s.count), 0.0)
    within = tol() if any(v is not None for v in (s.played_at, s.stopped_at, s.duration)) else 0.0
    measured = f"started at {fmt(times)}"
    if s.played_at is not None:
        played_at = float(s.played_at)
        nearest = min(times, key=lambda t: abs(t - played_at)) if times else None
        numbers = (nearest, played_at, within)
        expected.append(f"played at {fmt(played_at)} ± {fmt(within)}")
        if not any(abs(t - played_at) <= within + TIME_EPS for t in times):
            problems.append("not played at that time")
    if s.stopped_at is not None or s.duration is not None:
        ends = [stop for _, stop in played if stop is not None]
        measured += f", stopped at {fmt(ends)}"
        if len(ends) < len(played):
            measured += f" (still playing at the end, t={t_end:.4f})"
    if s.stopped_at is not None:
        goal = float(s.stopped_at)
        ends = [stop for _, stop in played if stop is not None]
        nearest = min(ends, key=lambda t: abs(t - goal)) if ends else None
        numbers = (nearest, goal, within)
        expected.append(f"stopped at {fmt(goal)} ± {fmt(within)}")
        if not any(abs(t - goal) <= within + TIME_EPS for t in ends):
            problems.append("not stopped at that time")
    if s.duration is not None:
        goal = float(s.duration)
        lengths = [stop - start for start, stop in played if stop is not None]
        measured += f", durations {fmt(lengths)}"
        numbers = (lengths[0] if lengths else None, goal, within)
        expected.append(f"every play {fmt(goal)} s ± {fmt(within)}")
        if not played:
            problems.append("never played")
        elif len(lengths) < len(played):
            problems.append("a play had not stopped by the end")
        elif any(abs(d - goal) > within + TIME_EPS for d in lengths):
            problems.append(f"played for {fmt(lengths)} s")
    if s.count is not None:
        lo, hi = _count_range(s.count)
        expected.append(f"count {lo}" if lo == hi else f"count in [{lo}, {hi}]")
        if len(times) < lo or (hi is not None and len(times) > hi):
            problems.append(f"played {len(times)} times")
    return Verdict(s.name, "sound", not problems, measured, ", ".join(expected), times[0] if times else None,
                   "; ".join(problems), value=numbers[0], target=numbers[1], tolerance=numbers[2])  # fmt: skip
