"""Verdicts, and the assertions decided at the end of a run from its events and sounds."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from runner.language import model_assertions as A
from runner.language.expressions import fmt

TIME_EPS = 1e-9


@dataclass
class Verdict:
    name: str
    kind: str
    passed: bool
    measured: str
    expected: str
    time: float | None = None  # when it was decided (first failure, first success, or the sample time)
    message: str = ""
    #: the numbers behind a numeric verdict, unformatted (None where the check is not numeric)
    value: float | None = None
    target: float | None = None
    tolerance: float | None = None

    def as_dict(self) -> dict[str, Any]:
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
        }


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
