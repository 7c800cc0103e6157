"""Assertion checking: running checks at every recorded step, and the verdicts at the end.

A verdict carries what was measured, in numbers: the value and the time of an extremum, the time a condition
became true, a sound's start and stop times; a failing condition carries the values of its sub-expressions at
the failing time (:meth:`runner.language.expressions.Expression.explain`), naming the member of a group.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from runner.language import model_assertions as A
from runner.language.expressions import Expression, Resolver, fmt
from runner.sim.verdicts import Verdict, apply_known_limit, event_verdict, sound_verdict, tolerance

__all__ = ["AssertionTracker", "Verdict", "fmt", "tolerance"]

TIME_EPS = 1e-9


def _window(during: tuple[Any, Any]) -> tuple[float, float]:
    lo, hi = during
    return (0.0 if lo == "end" else float(lo)), (math.inf if hi == "end" else float(hi))


@dataclass
class _Check:
    """The running state of one assertion."""

    spec: Any
    kind: str
    done: Verdict | None = None
    best: float | None = None
    best_time: float | None = None
    seen: bool = False
    previous: bool | None = None  # becomes: the condition at the last step
    extra: dict[str, Any] = field(default_factory=dict)
    #: how the running check treats it each step (``_route``), decided once from the spec's type
    route: str = ""
    #: an `at:` check's step (its time's nearest step; None: `at: end`)
    at_step: int | None = None
    #: a window or extremum check's times (``_window`` of its `during`), and a window check's condition (None:
    #: a contact's), made once
    lo: float = 0.0
    hi: float = math.inf
    text: str | None = None


def _route(spec: Any, dt: float) -> tuple[str, int | None]:
    """What ``AssertionTracker._on_step`` does with an assertion each step, and an `at:` check's step."""
    at = getattr(spec, "at", None)
    if isinstance(spec, A.ValueAssertion | A.CheckAssertion | A.ContactAssertion) and at is not None:
        return "at", None if at == "end" else math.floor(float(at) / dt + 0.5 + 1e-9)
    if isinstance(spec, A.AlwaysAssertion | A.NeverAssertion | A.EventuallyAssertion | A.ContactAssertion):
        return "window", None
    if isinstance(spec, A.MaxAssertion | A.MinAssertion):
        return "extremum", None
    if isinstance(spec, A.BecomesAssertion):
        return "becomes", None
    return "", None  # decided at the end (events, sounds)


class AssertionTracker:
    def __init__(self, specs: Sequence[Any], expressions: dict[str, Expression], backend: str, dt: float) -> None:
        self.backend = backend
        self.dt = dt
        self.expr = expressions
        self.checks = [_Check(s, type(s).__name__.removesuffix("Assertion").lower(), route=route, at_step=at_step)
                       for s in specs for route, at_step in (_route(s, dt),)]  # fmt: skip
        for c in self.checks:
            if c.route in ("window", "extremum"):
                c.lo, c.hi = _window(c.spec.during)
            if c.route == "window":
                c.text = None if isinstance(c.spec, A.ContactAssertion) else str(getattr(c.spec, c.kind))
        #: the checks still running each step, in order (decided ones leave it)
        self._running = [c for c in self.checks if c.route]
        self.decided: list[Verdict] = []  # verdicts decided since the last pop_decided(), in order

    def pop_decided(self) -> list[Verdict]:
        """The verdicts decided since the last call (the session logs each at the time it was decided)."""
        out, self.decided = self.decided, []
        return out

    def _number(self, value: Any, r: Resolver) -> float:
        return self.expr[value].number(r) if isinstance(value, str) else float(value)

    def _tolerance(self, tol: Any, r: Resolver) -> float:
        return self._number(tolerance(tol, self.backend), r)

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

    def _why(self, text: str, t: float, r: Resolver, value: str) -> str:
        """`false at t=4.0000: box.pos.z = 0.05, ...`: the sub-expressions' values when a condition failed."""
        detail = self.expr[text].explain(r)
        return f"{value} at t={t:.4f}" + (f": {detail}" if detail else "")

    def on_step(self, t: float, r: Resolver, contact: Callable[[str, str], bool], final: bool = False) -> None:
        if not self._running:
            return
        self._on_step(t, r, contact, final)
        if any(c.done is not None for c in self._running):
            for c in self._running:
                if c.done is not None:
                    c.done = self._limited(c.done, c.spec)
                    self.decided.append(c.done)
            self._running = [c for c in self._running if c.done is None]

    def _limited(self, v: Verdict, spec: Any) -> Verdict:
        return apply_known_limit(v, getattr(spec, "known_limits", {}), self.backend)

    def _on_step(self, t: float, r: Resolver, contact: Callable[[str, str], bool], final: bool) -> None:
        step: int | None = None  # the recorded step nearest to t (as _at_time), when an `at:` check asks
        for c in self._running:
            s, route = c.spec, c.route
            if route == "at":
                if c.at_step is None:
                    hit = final
                else:
                    if step is None:
                        step = math.floor(t / self.dt + 0.5)
                    hit = step == c.at_step
                if hit:
                    c.done = self._sample(s, t, r, contact)
                continue
            if route == "window":
                self._over_window(c, t, r, contact)
            elif route == "extremum":
                hi = c.hi
                if c.lo - TIME_EPS <= t <= hi + TIME_EPS:
                    is_max = isinstance(s, A.MaxAssertion)
                    of = s.max_of if isinstance(s, A.MaxAssertion) else s.min_of
                    number = self.expr[of].number(r)
                    if c.best is None or (number > c.best if is_max else number < c.best) or math.isnan(number):
                        c.best, c.best_time = number, t
                    if c.best is not None and hi <= t + TIME_EPS:
                        c.done = self._extremum(c, r)
            elif route == "becomes":
                self._becomes(c, t, r)

    def _over_window(self, c: _Check, t: float, r: Resolver, contact: Callable[[str, str], bool]) -> None:
        if t < c.lo - TIME_EPS or t > c.hi + TIME_EPS:
            return
        c.seen = True
        s, text = c.spec, c.text
        if text is None:  # a contact assertion
            value, mode = contact(*s.contact), str(s.when)
        else:
            mode = c.kind
            value = self.expr[text].truth(r)
        if mode == "always" and not value:
            why = self._why(text, t, r, "false") if text else f"not touching at t={t:.4f}"
            c.done = Verdict(s.name, c.kind, False, "false", "always true", t, why)
        elif mode == "never" and value:
            why = self._why(text, t, r, "true") if text else f"touching at t={t:.4f}"
            c.done = Verdict(s.name, c.kind, False, "true", "never true", t, why)
        elif mode == "eventually" and value:
            c.done = Verdict(s.name, c.kind, True, "true", "eventually true", t, f"true at t={t:.4f}")

    def _becomes(self, c: _Check, t: float, r: Resolver) -> None:
        s: A.BecomesAssertion = c.spec
        now = self.expr[s.becomes].truth(r)
        if c.previous is None:  # the first state: a rising edge needs false first
            c.previous = now
            c.extra["true_from_start"] = now
            return
        if now and not c.previous:
            c.done = self._became(s, t, r)
        c.previous = now
        if not now:
            c.extra["true_from_start"] = False

    def _became(self, s: A.BecomesAssertion, t: float, r: Resolver) -> Verdict:
        if s.within is not None:
            lo, hi = _window(s.within)
            ok = lo - TIME_EPS <= t <= hi + TIME_EPS
            expected = f"becomes true in [{fmt(lo)}, {fmt(hi) if math.isfinite(hi) else 'end'}]"
            return Verdict(s.name, "becomes", ok, f"became true at t={t:.6g}", expected, t, value=t)
        target = math.inf if s.near == "end" else float(s.near)  # type: ignore[arg-type]
        tol = self._number(tolerance(s.tol, self.backend), r)
        ok = abs(t - target) <= tol + TIME_EPS
        expected = f"becomes true at {fmt(target)} ± {fmt(tol)}"
        return Verdict(s.name, "becomes", ok, f"became true at t={t:.6g}", expected, t, value=t, target=target,
                       tolerance=tol)  # fmt: skip

    def _sample(self, s: Any, t: float, r: Resolver, contact: Callable[[str, str], bool]) -> Verdict:
        kind = type(s).__name__.removesuffix("Assertion").lower()
        if isinstance(s, A.CheckAssertion):
            ok = self.expr[s.check].truth(r)
            return Verdict(s.name, kind, ok, fmt(ok), "true", t, "" if ok else self._why(s.check, t, r, "false"))
        if isinstance(s, A.ContactAssertion):
            ok = contact(*s.contact)
            return Verdict(s.name, kind, ok, fmt(ok), "touching", t)
        measured = self.expr[s.value].evaluate(r)
        value = math.nan if isinstance(measured, list) else self.expr[s.value].number(r)
        detail = self.expr[s.value].explain(r)
        if s.near is not None:
            ok, expected, target, tol = self._near(value, s.near, s.tol, r)
            why = "" if ok else detail
            return Verdict(s.name, kind, ok, fmt(value), expected, t, why, value=value, target=target, tolerance=tol)
        lo = self._number(s.min, r) if s.min is not None else -math.inf
        hi = self._number(s.max, r) if s.max is not None else math.inf
        ok = lo <= value <= hi
        return Verdict(s.name, kind, ok, fmt(value), f"in [{fmt(lo)}, {fmt(hi)}]", t, "" if ok else detail, value=value)

    def _extremum(self, c: _Check, r: Resolver) -> Verdict:
        s = c.spec
        which = "max" if isinstance(s, A.MaxAssertion) else "min"
        best = c.best if c.best is not None else math.nan
        when = c.best_time
        measured = fmt(c.best)
        ok, expected_parts, problems = True, [], []
        target = tol = None
        if s.near is not None:
            near_ok, expected, target, tol = self._near(best, s.near, s.tol, r)
            ok &= near_ok
            expected_parts.append(expected)
            if not near_ok:
                problems.append(f"{which} {fmt(best)}")
        if s.time is not None:
            goal = math.inf if s.time == "end" else float(s.time)
            within = self._number(tolerance(s.time_tol, self.backend), r)
            time_ok = when is not None and abs(when - goal) <= within + TIME_EPS
            ok &= time_ok
            expected_parts.append(f"at t={fmt(goal)} ± {fmt(within)}")
            if not time_ok:
                problems.append(f"reached at t={fmt(when)}")
        if s.time_within is not None:
            lo, hi = _window(s.time_within)
            time_ok = when is not None and lo - TIME_EPS <= when <= hi + TIME_EPS
            ok &= time_ok
            expected_parts.append(f"at t in [{fmt(lo)}, {fmt(hi) if math.isfinite(hi) else 'end'}]")
            if not time_ok:
                problems.append(f"reached at t={fmt(when)}")
        message = f"{which} at t={when:.4f}" if when is not None else ""
        if problems:
            message = "; ".join(problems)
        value = best if s.near is not None else (when if when is not None else math.nan)
        return Verdict(s.name, c.kind, ok, measured, ", ".join(expected_parts), when, message, value=value,
                       target=target, tolerance=tol)  # fmt: skip

    def finish(
        self,
        t_end: float,
        events: Sequence[tuple[float, str]],
        sounds: Sequence[tuple[float, str]],
        r: Resolver,
        sound_stops: Sequence[tuple[float, str]] = (),
    ) -> list[Verdict]:
        out = []
        for c in self.checks:
            s = c.spec
            if c.done is not None:
                out.append(c.done)
            elif isinstance(s, A.EventAssertion | A.SoundAssertion):
                tol = partial(self._tolerance, s.tol, r)
                if isinstance(s, A.EventAssertion):
                    out.append(event_verdict(s, events, tol))
                else:
                    out.append(sound_verdict(s, sounds, sound_stops, tol, t_end))
            elif isinstance(s, A.MaxAssertion | A.MinAssertion):
                out.append(
                    self._extremum(c, r)
                    if c.best is not None
                    else Verdict(s.name, c.kind, False, "no sample", "a sample in the window", None,
                                 "the run ended before the window")  # fmt: skip
                )
            elif isinstance(s, A.BecomesAssertion):
                never = "true from the start and never false" if c.extra.get("true_from_start") else "never true"
                out.append(Verdict(s.name, c.kind, False, never, "becomes true (false before)", None,
                                   f"{never} up to t={t_end:.4f}"))  # fmt: skip
            elif isinstance(s, A.AlwaysAssertion | A.NeverAssertion) or (
                isinstance(s, A.ContactAssertion) and s.when in ("always", "never")
            ):
                ok = c.seen
                out.append(Verdict(s.name, c.kind, ok, "held" if ok else "no sample", "held over the window", t_end,
                                   "" if ok else "the run ended before the window"))  # fmt: skip
            elif isinstance(s, A.EventuallyAssertion) or isinstance(s, A.ContactAssertion) and s.when == "eventually":
                out.append(
                    Verdict(s.name, c.kind, False, "never true", "eventually true", None, "never true in the window")
                )
            else:
                at = getattr(s, "at", None)
                out.append(Verdict(s.name, c.kind, False, "not reached", f"a sample at t={at}", None,
                                   f"the run ended at t={t_end:.4f} before t={at}"))  # fmt: skip
        out = [v if c.done is not None else self._limited(v, c.spec) for v, c in zip(out, self.checks, strict=True)]
        self.decided += [v for v, c in zip(out, self.checks, strict=True) if c.done is None]  # decided now
        return out
