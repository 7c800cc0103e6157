"""The conformance suite's cases: every variant of every scenario in the suite's folder, with its checks.

A case is one scenario file and one of its variants (or its base case). Its checks are its assertions, with
the expectation written as text (the analytic formula) and the tolerance per backend, as the matrix shows
them. The suite lives in ``scenarios/conformance/`` of the source tree; ``--suite`` points elsewhere.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from runner.errors import ScenarioValidationError
from runner.language import model_assertions as A
from runner.language.load import BASE_CASE, load_scenario, variant_names

#: The suite of the source tree (the package is installed from it, editable or not).
DEFAULT_SUITE = Path(__file__).resolve().parents[2] / "scenarios" / "conformance"


@dataclass(frozen=True)
class Check:
    """One assertion of a case, as the matrix shows it."""

    name: str
    kind: str  # value, max, min, becomes, event, sound, check, always, never, eventually, contact
    measure: str  # what is measured: "box.vel.z at 0.04", "max(abs(...)) over [1, end]", "event s1"
    expected: str  # what is expected of it: a formula, a range, a condition, times
    tolerance: dict[str, str] = field(default_factory=dict)  # backend (or "default") -> tolerance text
    description: str = ""
    #: backend -> {measured, cause, doc}: engines that cannot meet the check (judged at the default tolerance)
    known_limits: dict[str, dict[str, Any]] = field(default_factory=dict)


@dataclass(frozen=True)
class Case:
    id: str  # "07_restitution" or "08_friction/launched"
    path: Path
    variant: str | None  # None: the base case
    scenario: str
    semantic: str  # the scenario's description
    variant_description: str
    checks: tuple[Check, ...]

    @property
    def file(self) -> str:
        return self.path.name

    def job(self) -> dict[str, Any]:
        """What a worker needs to run the case."""
        return {"id": self.id, "path": str(self.path), "variant": self.variant}


def _text(value: Any) -> str:
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    if isinstance(value, float):
        return f"{value:.6g}"  # a time written as an expression is known here by its value
    return " ".join(str(value).split())


def _tolerance(tol: Any) -> dict[str, str]:
    if isinstance(tol, dict):
        return {k: _text(v) for k, v in tol.items()}
    return {"default": _text(tol)}


def _range(lo: Any, hi: Any) -> str:
    if lo is not None and hi is not None:
        return f"in [{_text(lo)}, {_text(hi)}]"
    return f">= {_text(lo)}" if lo is not None else f"<= {_text(hi)}"


def _times(count: Any) -> str:
    if isinstance(count, int):
        return "once" if count == 1 else f"{count} times"
    return f"{_range(count.min, count.max)} times"


def _window(during: Any) -> str:
    return "" if tuple(during) == (0.0, "end") else f" over [{_text(during[0])}, {_text(during[1])}]"


def describe(s: Any) -> Check:
    """The matrix's view of an assertion: what is measured, what is expected of it, its known limits."""
    check = _describe(s)
    limits = {b: limit.model_dump() for b, limit in s.known_limits.items()}
    return replace(check, known_limits=limits) if limits else check


def _describe(s: Any) -> Check:  # noqa: C901 - one switch over the assertion kinds
    kind = type(s).__name__.removesuffix("Assertion").lower()
    description = " ".join((s.description or "").split())
    if isinstance(s, A.ValueAssertion):
        measure = f"{_text(s.value)} at {_text(s.at)}"
        if s.near is None:
            return Check(s.name, kind, measure, _range(s.min, s.max), {}, description)
        return Check(s.name, kind, measure, _text(s.near), _tolerance(s.tol), description)
    if isinstance(s, A.MaxAssertion | A.MinAssertion):
        of = s.max_of if isinstance(s, A.MaxAssertion) else s.min_of
        measure = f"{kind}({_text(of)}){_window(s.during)}"
        parts = [_text(s.near)] if s.near is not None else []
        parts += [f"at t = {_text(s.time)} ± {_text(s.time_tol)}"] if s.time is not None else []
        parts += [f"at t in [{_text(s.time_within[0])}, {_text(s.time_within[1])}]"] if s.time_within else []
        return Check(s.name, kind, measure, ", ".join(parts), _tolerance(s.tol) if s.near is not None else {},
                     description)  # fmt: skip
    if isinstance(s, A.BecomesAssertion):
        if s.within is not None:
            return Check(s.name, kind, f"when {_text(s.becomes)} becomes true",
                         f"in [{_text(s.within[0])}, {_text(s.within[1])}]", {}, description)  # fmt: skip
        return Check(s.name, kind, f"when {_text(s.becomes)} becomes true", _text(s.near), _tolerance(s.tol),
                     description)  # fmt: skip
    if isinstance(s, A.EventAssertion):
        parts = [f"first at {_text(s.first)}"] if s.first is not None else []
        parts += [_times(s.count)] if s.count is not None else []
        parts += [f"before {s.before}"] if s.before is not None else []
        parts += [f"after {s.after}"] if s.after is not None else []
        tol = _tolerance(s.tol) if s.first is not None else {}
        return Check(s.name, kind, f"event {s.event}", ", ".join(parts), tol, description)
    if isinstance(s, A.SoundAssertion):
        parts = [f"started at {_text(s.played_at)}"] if s.played_at is not None else []
        parts += [f"stopped at {_text(s.stopped_at)}"] if s.stopped_at is not None else []
        parts += [f"lasted {_text(s.duration)} s"] if s.duration is not None else []
        parts += [_times(s.count)] if s.count is not None else []
        timed = any(v is not None for v in (s.played_at, s.stopped_at, s.duration))
        tol = _tolerance(s.tol) if timed else {}
        return Check(s.name, kind, f"sound {s.sound}", ", ".join(parts), tol, description)
    if isinstance(s, A.CheckAssertion):
        return Check(s.name, kind, f"at {_text(s.at)}", _text(s.check), {}, description)
    if isinstance(s, A.ContactAssertion):
        when = f"at {_text(s.at)}" if s.at is not None else f"{s.when}{_window(s.during)}"
        return Check(s.name, kind, f"contact({s.contact[0]}, {s.contact[1]})", when, {}, description)
    condition = getattr(s, kind, "")
    return Check(s.name, kind, f"{kind}{_window(s.during)}", _text(condition), {}, description)


def discover(suite: Path) -> list[Case]:
    """Every case of every ``*.yaml`` file in ``suite``, in file-name order; all problems at once."""
    if not suite.is_dir():
        raise ScenarioValidationError([_issue(suite, "expected a folder of conformance scenarios")])
    files = sorted(suite.glob("*.yaml"))
    if not files:
        raise ScenarioValidationError([_issue(suite, "expected conformance scenarios (*.yaml), found none")])
    cases: list[Case] = []
    problems = []
    for path in files:
        try:
            names = variant_names(path)
            for name in names:
                variant = None if name == BASE_CASE else name
                loaded = load_scenario(path, variant)
                model = loaded.model
                description = "" if variant is None else (model.variants[variant].description or "")
                cases.append(
                    Case(
                        id=path.stem if variant is None else f"{path.stem}/{variant}",
                        path=path.resolve(),
                        variant=variant,
                        scenario=model.scenario,
                        semantic=" ".join((model.description or model.scenario).split()),
                        variant_description=" ".join(description.split()),
                        checks=tuple(describe(a) for a in model.assertions),
                    )
                )
        except ScenarioValidationError as exc:
            problems.extend(exc.issues)
    if problems:
        raise ScenarioValidationError(problems)
    return cases


def _issue(path: Path, message: str) -> Any:
    from runner.errors import Issue

    return Issue(str(path), 0, 0, "", message)
