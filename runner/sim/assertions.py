"""Assertion checking: running checks at every recorded step, and the verdicts at the end."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from runner.language import model_assertions as A
from runner.language.expressions import Expression, Resolver

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


def fmt(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return str(value).lower()
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(fmt(v) for v in value[:6]) + (", ..." if len(value) > 6 else "") + "]"
    return str(value)


def tolerance(tol: Any, backend: str) -> Any:
    """The tolerance for ``backend``: a number, or an expression's text (evaluated by the caller)."""
    if isinstance(tol, dict):
        return tol.get(backend, tol.get("default", 0.0))
    return tol


def _window(during: tuple[Any, Any]) -> tuple[float, float]:
    lo, hi = during
    return (0.0 if lo == "end" else float(lo)), (math.inf if hi == "end" else float(hi))


def _time(at: Any) -> float:
    return math.inf if at == "end" else float(at)


@dataclass
class _Check:
    """The running state of one assertion."""

    spec: Any
    kind: str
    done: Verdict | None = None
    best: float | None = None
    best_time: float | None = None
    seen: bool = False
    extra: dict[str, Any] = field(default_factory=dict)


class AssertionTracker:
    def __init__(self, specs: Sequence[Any], expressions: dict[str, Expression], backend: str, dt: float) -> None:
        self.backend = backend
        self.dt = dt
        self.expr = expressions
        self.checks = [_Check(s, type(s).__name__.removesuffix("Assertion").lower()) for s in specs]
        self.decided: list[Verdict] = []  # verdicts decided since the last pop_decided(), in order

    def pop_decided(self) -> list[Verdict]:
        """The verdicts decided since the last call (the session logs each at the time it was decided)."""
        out, self.decided = self.decided, []
        return out

    def _number(self, value: Any, r: Resolver) -> float:
        return self.expr[value].number(r) if isinstance(value, str) else float(value)

    def _near(self, measured: float, near: Any, tol: Any, r: Resolver) -> tuple[bool, str, float, float]:
        target = self._number(near, r)
        t = self._number(tolerance(tol, self.backend), r)
        ok = math.isfinite(measured) and abs(measured - target) <= t + 1e-12 * max(1.0, abs(target))
        return ok, f"{fmt(target)} ± {fmt(t)}", target, t

    def _at_time(self, at: Any, t: float, final: bool) -> bool:
        if at == "end":
            return final
        # the recorded step nearest to `at` (ties go to the later step, as Panda3D's frame would show it)
        return math.floor(t / self.dt + 0.5) == math.floor(float(at) / self.dt + 0.5 + 1e-9)

    def on_step(self, t: float, r: Resolver, contact: Callable[[str, str], bool], final: bool = False) -> None:
        pending = [c for c in self.checks if c.done is None]
        self._on_step(t, r, contact, final)
        self.decided += [c.done for c in pending if c.done is not None]

    def _on_step(self, t: float, r: Resolver, contact: Callable[[str, str], bool], final: bool) -> None:
        for c in self.checks:
            if c.done is not None:
                continue
            s = c.spec
            if (
                isinstance(s, A.ValueAssertion | A.CheckAssertion | A.ContactAssertion)
                and getattr(s, "at", None) is not None
            ):
                if self._at_time(s.at, t, final):
                    c.done = self._sample(s, t, r, contact)
                continue
            if isinstance(s, A.AlwaysAssertion | A.NeverAssertion | A.EventuallyAssertion | A.ContactAssertion):
                lo, hi = _window(s.during)
                if t < lo - TIME_EPS or t > hi + TIME_EPS:
                    continue
                c.seen = True
                if isinstance(s, A.ContactAssertion):
                    value = contact(*s.contact)
                    mode = s.when
                else:
                    mode = (
                        "always"
                        if isinstance(s, A.AlwaysAssertion)
                        else ("never" if isinstance(s, A.NeverAssertion) else "eventually")
                    )
                    value = self.expr[getattr(s, mode)].truth(r)
                if mode == "always" and not value:
                    c.done = Verdict(s.name, c.kind, False, "false", "always true", t, f"false at t={t:.4f}")
                elif mode == "never" and value:
                    c.done = Verdict(s.name, c.kind, False, "true", "never true", t, f"true at t={t:.4f}")
                elif mode == "eventually" and value:
                    c.done = Verdict(s.name, c.kind, True, "true", "eventually true", t, f"true at t={t:.4f}")
            elif isinstance(s, A.MaxAssertion | A.MinAssertion):
                lo, hi = _window(s.during)
                if lo - TIME_EPS <= t <= hi + TIME_EPS:
                    is_max = isinstance(s, A.MaxAssertion)
                    of = s.max_of if isinstance(s, A.MaxAssertion) else s.min_of
                    number = self.expr[of].number(r)
                    if c.best is None or (number > c.best if is_max else number < c.best) or math.isnan(number):
                        c.best, c.best_time = number, t
                    c.extra["r_time"] = t
                    if c.best is not None and hi <= t + TIME_EPS:
                        c.done = self._extremum(c, r)

    def _sample(self, s: Any, t: float, r: Resolver, contact: Callable[[str, str], bool]) -> Verdict:
        kind = type(s).__name__.removesuffix("Assertion").lower()
        if isinstance(s, A.CheckAssertion):
            ok = self.expr[s.check].truth(r)
            return Verdict(s.name, kind, ok, fmt(ok), "true", t)
        if isinstance(s, A.ContactAssertion):
            ok = contact(*s.contact)
            return Verdict(s.name, kind, ok, fmt(ok), "touching", t)
        measured = self.expr[s.value].evaluate(r)
        value = math.nan if isinstance(measured, list) else self.expr[s.value].number(r)
        if s.near is not None:
            ok, expected, target, tol = self._near(value, s.near, s.tol, r)
            return Verdict(s.name, kind, ok, fmt(value), expected, t, value=value, target=target, tolerance=tol)
        lo = self._number(s.min, r) if s.min is not None else -math.inf
        hi = self._number(s.max, r) if s.max is not None else math.inf
        ok = lo <= value <= hi
        return Verdict(s.name, kind, ok, fmt(value), f"in [{fmt(lo)}, {fmt(hi)}]", t, value=value)

    def _extremum(self, c: _Check, r: Resolver) -> Verdict:
        s = c.spec
        best = c.best if c.best is not None else math.nan
        ok, expected, target, tol = self._near(best, s.near, s.tol, r)
        return Verdict(
            s.name,
            c.kind,
            ok,
            fmt(c.best),
            expected,
            c.best_time,
            f"{'max' if isinstance(s, A.MaxAssertion) else 'min'} at t={c.best_time:.4f}"
            if c.best_time is not None
            else "",
            value=best,
            target=target,
            tolerance=tol,
        )

    def finish(
        self, t_end: float, events: Sequence[tuple[float, str]], sounds: Sequence[tuple[float, str]], r: Resolver
    ) -> list[Verdict]:
        out = []
        for c in self.checks:
            s = c.spec
            if c.done is not None:
                out.append(c.done)
            elif isinstance(s, A.EventAssertion):
                out.append(self._event(s, events, r))
            elif isinstance(s, A.SoundAssertion):
                out.append(self._sound(s, sounds, r))
            elif isinstance(s, A.MaxAssertion | A.MinAssertion):
                out.append(
                    self._extremum(c, r)
                    if c.best is not None
                    else Verdict(
                        s.name,
                        c.kind,
                        False,
                        "no sample",
                        "a sample in the window",
                        None,
                        "the run ended before the window",
                    )
                )
            elif isinstance(s, A.AlwaysAssertion | A.NeverAssertion) or (
                isinstance(s, A.ContactAssertion) and s.when in ("always", "never")
            ):
                ok = c.seen
                out.append(
                    Verdict(
                        s.name,
                        c.kind,
                        ok,
                        "held" if ok else "no sample",
                        "held over the window",
                        t_end,
                        "" if ok else "the run ended before the window",
                    )
                )
            elif isinstance(s, A.EventuallyAssertion) or isinstance(s, A.ContactAssertion) and s.when == "eventually":
                out.append(
                    Verdict(s.name, c.kind, False, "never true", "eventually true", None, "never true in the window")
                )
            else:
                at = getattr(s, "at", None)
                out.append(
                    Verdict(
                        s.name,
                        c.kind,
                        False,
                        "not reached",
                        f"a sample at t={at}",
                        None,
                        f"the run ended at t={t_end:.4f} before t={at}",
                    )
                )
        self.decided += [v for v, c in zip(out, self.checks, strict=True) if c.done is None]  # decided now
        return out

    def _event(self, s: A.EventAssertion, events: Sequence[tuple[float, str]], r: Resolver) -> Verdict:
        times = [t for t, name in events if name == s.event]
        first = times[0] if times else None
        problems, measured, expected = [], [f"count {len(times)}", f"first {fmt(first)}"], []
        numbers: tuple[float | None, float | None, float | None] = (None, None, None)
        if isinstance(s.count, int):
            numbers = (float(len(times)), float(s.count), 0.0)
        if s.count is not None:
            lo, hi = (s.count, s.count) if isinstance(s.count, int) else (s.count.min, s.count.max)
            expected.append(f"count {lo}" if lo == hi else f"count in [{lo}, {hi if hi is not None else '∞'}]")
            if len(times) < lo or (hi is not None and len(times) > hi):
                problems.append(f"happened {len(times)} times")
        if s.first is not None:
            within = self._number(tolerance(s.tol, self.backend), r)
            first_at = _time(s.first)
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
        value, target, tol = numbers
        return Verdict(
            s.name,
            "event",
            not problems,
            ", ".join(measured),
            ", ".join(expected),
            first,
            "; ".join(problems),
            value=value,
            target=target,
            tolerance=tol,
        )

    def _sound(self, s: A.SoundAssertion, sounds: Sequence[tuple[float, str]], r: Resolver) -> Verdict:
        times = [t for t, name in sounds if name == s.sound]
        problems, expected = [], []
        numbers: tuple[float | None, float | None, float | None] = (None, None, None)
        if isinstance(s.count, int):
            numbers = (float(len(times)), float(s.count), 0.0)
        if s.played_at is not None:
            tol = self._number(tolerance(s.tol, self.backend), r)
            played_at = float(s.played_at)
            nearest = min(times, key=lambda t: abs(t - played_at)) if times else None
            numbers = (nearest, played_at, tol)
            expected.append(f"played at {fmt(played_at)} ± {fmt(tol)}")
            if not any(abs(t - played_at) <= tol + TIME_EPS for t in times):
                problems.append("not played at that time")
        if s.count is not None:
            lo, hi = (s.count, s.count) if isinstance(s.count, int) else (s.count.min, s.count.max)
            expected.append(f"count {lo}" if lo == hi else f"count in [{lo}, {hi}]")
            if len(times) < lo or (hi is not None and len(times) > hi):
                problems.append(f"played {len(times)} times")
        return Verdict(
            s.name,
            "sound",
            not problems,
            f"started at {fmt(times)}",
            ", ".join(expected),
            times[0] if times else None,
            "; ".join(problems),
            value=numbers[0],
            target=numbers[1],
            tolerance=numbers[2],
        )
