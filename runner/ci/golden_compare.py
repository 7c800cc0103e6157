"""Comparing a run's recording with its golden file: per-field tolerances, the first divergence, what moved.

A sampled value diverges when |got - expected| > atol + rtol * |expected| (tolerances from
:class:`runner.ci.golden.Tolerances`); quaternions are compared after choosing the sign closest to the golden's
(q and -q are one rotation). Events and sounds must have the same names and sources in the same order, their
times within the `event` tolerance; verdicts must pass or fail as recorded. A signal has *moved* when it
differs at all beyond the file's 9-digit rounding, inside the tolerance or not: that list is what an engine
upgrade warning names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from runner.ci.golden import BODY_FIELDS, JOINT_FIELDS, Recording, Tolerances, _num

ROUNDING_ATOL = 2e-9  # the trace's 1e-9 resolution, twice
ROUNDING_RTOL = 1e-8  # 9 significant digits


@dataclass(frozen=True)
class Divergence:
    time: float
    kind: str  # body | joint | var | event | sound | verdict | run
    name: str
    field: str  # e.g. pos.z, position, time, order, missing
    expected: str
    got: str
    tolerance: str = ""
    excess: float = math.inf  # the difference over its tolerance: at equal times the largest comes first

    @property
    def signal(self) -> str:
        return f"{self.name}.{self.field}" if self.field else self.name

    def describe(self) -> str:
        tol = f" (tolerance {self.tolerance})" if self.tolerance else ""
        return (
            f"t={_num(self.time)} s, {self.kind} `{self.name}`, {self.field or '-'}: "
            f"expected {self.expected}, got {self.got}{tol}"
        )


@dataclass(frozen=True)
class SignalChange:
    """A signal that differs from the golden at all: its largest difference and the first time beyond tolerance."""

    kind: str
    name: str
    field: str
    max_error: float
    at: float
    first_over: float | None

    @property
    def signal(self) -> str:
        return f"{self.name}.{self.field}"

    def describe(self) -> str:
        if not math.isfinite(self.max_error):
            return f"{self.signal} (changed at {_num(self.at)} s)"
        over = f", out of tolerance from {_num(self.first_over)} s" if self.first_over is not None else ""
        return f"{self.signal} (max {self.max_error:.3g} at {_num(self.at)} s{over})"


@dataclass
class Comparison:
    expected: Recording
    got: Recording
    divergences: list[Divergence] = field(default_factory=list)  # sorted by time: the first is the first
    changes: list[SignalChange] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.divergences

    @property
    def first(self) -> Divergence | None:
        return self.divergences[0] if self.divergences else None

    def version_warning(self, limit: int = 8) -> str | None:
        """When the engine versions differ: the two versions and the signals that moved."""
        old, new = self.expected.header.get("engine"), self.got.header.get("engine")
        if old == new:
            return None
        backend = self.got.header.get("backend", "?")
        text = f"{backend} {new} is installed but the baseline was recorded with {old}; "
        if not self.changes:
            return text + "no signal moved"
        moved = ", ".join(c.describe() for c in self.changes[:limit])
        more = f" and {len(self.changes) - limit} more" if len(self.changes) > limit else ""
        return text + f"signals that moved: {moved}{more}"


def compare(expected: Recording, got: Recording, tolerances: Tolerances) -> Comparison:
    out = Comparison(expected, got)
    _notes(out)
    n = _align(out)
    times = expected.times[:n]
    _named(out, "body", expected.bodies, got.bodies, lambda name, e, g: _body(out, tolerances, name, e, g, times), n)
    _named(out, "joint", expected.joints, got.joints, lambda name, e, g: _joint(out, tolerances, name, e, g, times), n)
    _named(out, "var", expected.state, got.state, lambda name, e, g: _var(out, tolerances, name, e, g, times), n)
    _sequence(out, "event", expected.events, got.events, tolerances)
    _sequence(out, "sound", expected.sounds, got.sounds, tolerances)
    _verdicts(out)
    out.divergences.sort(key=lambda d: (d.time, -d.excess))
    out.changes.sort(key=lambda c: (c.first_over is None, c.first_over or 0.0, -c.max_error))
    return out


def _notes(out: Comparison) -> None:
    e, g = out.expected.header, out.got.header
    if e.get("scenario_sha256") != g.get("scenario_sha256"):
        out.notes.append(
            f"the scenario file differs from the one the baseline was recorded with ({e.get('scenario_file')})"
        )
    if e.get("tool") != g.get("tool"):
        out.notes.append(f"physics-scenarios {g.get('tool')} ran; the baseline was recorded with {e.get('tool')}")


def _align(out: Comparison) -> int:
    """Rows to compare; a different sampling or length is itself a divergence."""
    e, g = out.expected, out.got
    if e.header.get("dt") != g.header.get("dt"):
        out.divergences.append(Divergence(0.0, "run", "dt", "", e.header.get("dt", "?"), g.header.get("dt", "?")))
        return 0
    n = min(len(e.steps), len(g.steps))
    k = next((i for i in range(n) if e.steps[i] != g.steps[i]), n)  # rows sampled at the same steps
    if k < len(e.steps) or k < len(g.steps):
        dt = float(e.header["dt"])
        t = min(s[k] for s in (e.steps, g.steps) if len(s) > k) * dt
        end_e, end_g = e.header.get("end_time", "?"), g.header.get("end_time", "?")
        out.divergences.append(Divergence(t, "run", "end", "", f"end at {end_e} s", f"end at {end_g} s"))
    if e.header.get("status") != g.header.get("status"):
        t = float(g.header.get("end_time", 0.0))
        out.divergences.append(
            Divergence(t, "run", "status", "", str(e.header.get("status")), str(g.header.get("status")))
        )
    return k


def _named(out: Comparison, kind: str, exp: dict[str, Any], got: dict[str, Any], each: Any, n: int) -> None:
    for name in exp:
        if name not in got:
            out.divergences.append(Divergence(0.0, kind, name, "missing", "present", "missing"))
        elif n:
            each(name, exp[name][:n], got[name][:n])
    for name in got:
        if name not in exp:
            out.divergences.append(Divergence(0.0, kind, name, "extra", "absent", "present"))


def _body(out: Comparison, tol: Tolerances, name: str, e: np.ndarray, g: np.ndarray, times: np.ndarray) -> None:
    i = 0
    for fld, keys in BODY_FIELDS:
        ev, gv = e[:, i : i + len(keys)], g[:, i : i + len(keys)]
        if fld == "quat":
            flip = np.nansum(ev * gv, axis=1) < 0
            gv = np.where(flip[:, None], -gv, gv)
        for j, key in enumerate(keys):
            _signal(out, tol, "body", name, fld, f"{fld}.{key}", ev[:, j], gv[:, j], times)
        i += len(keys)


def _joint(out: Comparison, tol: Tolerances, name: str, e: np.ndarray, g: np.ndarray, times: np.ndarray) -> None:
    for j, fld in enumerate(JOINT_FIELDS):
        _signal(out, tol, "joint", name, fld, fld, e[:, j], g[:, j], times)


def _var(out: Comparison, tol: Tolerances, name: str, e: list[Any], g: list[Any], times: np.ndarray) -> None:
    numeric = all(_is_number(v) for v in e) and all(_is_number(v) for v in g)
    if numeric:
        _signal(out, tol, "var", name, "state", "value", np.array(e, float), np.array(g, float), times)
        return
    for i, (a, b) in enumerate(zip(e, g, strict=True)):
        if a != b:
            out.divergences.append(Divergence(float(times[i]), "var", name, "value", _show(a), _show(b)))
            out.changes.append(SignalChange("var", name, "value", math.inf, float(times[i]), float(times[i])))
            return


def _signal(
    out: Comparison, tol: Tolerances, kind: str, name: str, fld: str, label: str,
    e: np.ndarray, g: np.ndarray, times: np.ndarray,
) -> None:  # fmt: skip
    atol, rtol = tol.lookup(name, fld)
    with np.errstate(invalid="ignore"):
        err = np.abs(g - e)
    same_nan = np.isnan(e) & np.isnan(g)
    err = np.where(same_nan, 0.0, np.where(np.isnan(err), np.inf, err))
    scale = np.abs(np.nan_to_num(e))
    moved = err > ROUNDING_ATOL + ROUNDING_RTOL * scale
    if not moved.any():
        return
    bound = atol + rtol * scale
    over = np.flatnonzero(err > bound)
    worst = int(np.argmax(err))
    first = float(times[over[0]]) if over.size else None
    out.changes.append(SignalChange(kind, name, label, float(err[worst]), float(times[worst]), first))
    if over.size:
        i = int(over[0])
        text = f"{bound[i]:.3g} = atol {atol:g} + rtol {rtol:g}·|expected|"
        excess = float(err[i] / bound[i]) if bound[i] > 0 else math.inf
        out.divergences.append(Divergence(float(times[i]), kind, name, label, _num(e[i]), _num(g[i]), text, excess))


def _sequence(
    out: Comparison, kind: str, exp: list[tuple[float, str, str]], got: list[tuple[float, str, str]], tol: Tolerances
) -> None:
    for i in range(max(len(exp), len(got))):
        if i >= len(got):
            t, name, src = exp[i]
            out.divergences.append(Divergence(t, kind, name, "missing", f"{name} ({src}) at {_num(t)} s", "no more"))
            return
        if i >= len(exp):
            t, name, src = got[i]
            out.divergences.append(Divergence(t, kind, name, "extra", "no more", f"{name} ({src}) at {_num(t)} s"))
            return
        (te, ne, se), (tg, ng, sg) = exp[i], got[i]
        if (ne, se) != (ng, sg):
            out.divergences.append(
                Divergence(
                    min(te, tg), kind, ne, "order", f"{ne} ({se}) at {_num(te)} s", f"{ng} ({sg}) at {_num(tg)} s"
                )
            )
            return
        atol, rtol = tol.lookup(ne, "event")
        err = abs(tg - te)
        if err > ROUNDING_ATOL + ROUNDING_RTOL * abs(te):
            bound = atol + rtol * abs(te)
            first = min(te, tg) if err > bound else None
            out.changes.append(SignalChange(kind, f"{ne}#{i + 1}", "time", err, te, first))
            if first is not None:
                text = f"{bound:.3g} = atol {atol:g} + rtol {rtol:g}·|expected|"
                excess = err / bound if bound > 0 else math.inf
                out.divergences.append(
                    Divergence(first, kind, ne, "time", f"{_num(te)} s", f"{_num(tg)} s", text, excess)
                )
                return


def _verdicts(out: Comparison) -> None:
    end = float(out.got.header.get("end_time", 0.0))
    got = {v.name: v for v in out.got.verdicts}
    names = {v.name for v in out.expected.verdicts}
    for v in out.expected.verdicts:
        g = got.get(v.name)
        if g is None:
            out.divergences.append(Divergence(end, "verdict", v.name, "missing", _pf(v.passed), "not checked"))
        elif g.passed != v.passed:
            t = g.time if g.time is not None and math.isfinite(g.time) else end
            out.divergences.append(
                Divergence(
                    t, "verdict", v.name, "result", f"{_pf(v.passed)} ({v.measured})", f"{_pf(g.passed)} ({g.measured})"
                )
            )
    for g in out.got.verdicts:
        if g.name not in names:
            out.divergences.append(Divergence(end, "verdict", g.name, "extra", "not checked", _pf(g.passed)))


def _pf(passed: bool) -> str:
    return "pass" if passed else "FAIL"


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _show(v: Any) -> str:
    return "true" if v is True else "false" if v is False else repr(v) if isinstance(v, str) else str(v)


def series(rec: Recording, kind: str, name: str, label: str) -> np.ndarray | None:
    """The sampled values of one signal (for plots), or None when the recording has no such signal."""
    if kind == "body" and name in rec.bodies:
        i = 0
        for fld, keys in BODY_FIELDS:
            for key in keys:
                if label == f"{fld}.{key}":
                    return rec.bodies[name][:, i]
                i += 1
    if kind == "joint" and name in rec.joints and label in JOINT_FIELDS:
        return rec.joints[name][:, JOINT_FIELDS.index(label)]
    if kind == "var" and name in rec.state and all(_is_number(v) for v in rec.state[name]):
        return np.array(rec.state[name], float)
    return None
