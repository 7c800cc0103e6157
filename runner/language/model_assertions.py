"""Named pass/fail assertions."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal, Union

from pydantic import Discriminator, Field, Tag, model_validator

from runner.language.model_actions import tag_of
from runner.language.model_base import EventName, Expr, Name, NonNegFloat, PartName, Seconds, Strict, TimeOrEnd, Window

Tolerance = Annotated[float, Field(ge=0, allow_inf_nan=False)] | Expr | dict[str, Annotated[float, Field(ge=0)] | Expr]
Number = float | Expr  # a number, or an expression evaluated when the assertion is checked


class KnownLimit(Strict):
    """An engine that cannot meet the assertion: an expected failure. Its check runs at the default tolerance;
    failing there is the verdict ``known limit`` (shown with the measured deviation and the cause, not
    failing the run), passing fails the run (the entry is no longer needed)."""

    measured: Annotated[float, Field(ge=0, allow_inf_nan=False)] = Field(
        description="The largest deviation |measured - expected| measured on this engine (the docs' figure)."
    )
    cause: Annotated[str, Field(min_length=1, max_length=300)] = Field(description="Why, in one line.")
    doc: Annotated[str, Field(min_length=1, max_length=300)] = Field(
        description="The document (path#anchor from the repository root) that explains it."
    )


class AssertionBase(Strict):
    name: Annotated[str, Field(min_length=1, max_length=128)]
    description: str | None = Field(None, max_length=2000)
    known_limits: dict[Name, KnownLimit] = Field(
        default_factory=dict,
        description="Engines that cannot meet this assertion (engine -> measured deviation, cause, doc); "
        "an expected failure on every execution path (run, CI, pytest, reports, the conformance matrix), "
        "and a failure when it passes.",
    )

    @model_validator(mode="after")
    def _limits_keep_the_default(self) -> AssertionBase:
        tol = getattr(self, "tol", None)
        both = sorted(set(self.known_limits) & set(tol)) if isinstance(tol, dict) else []
        if both:
            raise ValueError(f"{', '.join(both)}: a known limit is judged at the default tolerance; remove its `tol`")
        return self


def _tol_check(tol: Any) -> None:
    if isinstance(tol, dict) and not tol:
        raise ValueError("expected a tolerance number or a map {default: x, <backend>: y}, found {}")


class ValueAssertion(AssertionBase):
    """`value` at a time: near a number within tol, or between min and max."""

    at: TimeOrEnd
    value: Expr
    near: Number | None = None
    tol: Tolerance = 0.0
    min: Number | None = None
    max: Number | None = None

    @model_validator(mode="after")
    def _how(self) -> ValueAssertion:
        if self.near is None and self.min is None and self.max is None:
            raise ValueError("expected `near` (with `tol`) or `min`/`max`, found none")
        _tol_check(self.tol)
        return self


class CheckAssertion(AssertionBase):
    """A condition that must hold at a time."""

    at: TimeOrEnd
    check: Expr


class AlwaysAssertion(AssertionBase):
    always: Expr
    during: Window = (0.0, "end")


class NeverAssertion(AssertionBase):
    never: Expr
    during: Window = (0.0, "end")


class EventuallyAssertion(AssertionBase):
    eventually: Expr
    during: Window = (0.0, "end")


class ExtremumBase(AssertionBase):
    """The largest (smallest) value of an expression over a window: its value near a number, and/or the time
    at which it is reached near a time or within a window (the first such time if it is reached twice)."""

    during: Window = (0.0, "end")
    near: Number | None = Field(None, description="The extremum's value should be near this.")
    tol: Tolerance = 0.0
    time: TimeOrEnd | None = Field(None, description="The time of the extremum should be near this.")
    time_tol: Tolerance = Field(0.0, description="Tolerance on `time`, seconds.")
    time_within: Window | None = Field(None, description="The time of the extremum should be in this window.")

    @model_validator(mode="after")
    def _how(self) -> ExtremumBase:
        if self.near is None and self.time is None and self.time_within is None:
            raise ValueError("expected `near` (the value), `time` or `time_within` (when); found none")
        _tol_check(self.tol)
        return self


class MaxAssertion(ExtremumBase):
    """The largest value of an expression over a window."""

    max_of: Expr = Field(alias="max")


class MinAssertion(ExtremumBase):
    """The smallest value of an expression over a window."""

    min_of: Expr = Field(alias="min")


class BecomesAssertion(AssertionBase):
    """The time a condition first becomes true (false before, true at a step: a crossing, an apex, a stop),
    near a time or within a window."""

    becomes: Expr
    near: TimeOrEnd | None = Field(None, description="It should become true near this time.")
    tol: Tolerance = Field(0.0, description="Tolerance on `near`, seconds.")
    within: Window | None = Field(None, description="It should become true in this window.")

    @model_validator(mode="after")
    def _how(self) -> BecomesAssertion:
        if (self.near is None) == (self.within is None):
            raise ValueError("expected exactly one of `near` (with `tol`) or `within`")
        _tol_check(self.tol)
        return self


class CountRange(Strict):
    min: Annotated[int, Field(ge=0)] = 0
    max: Annotated[int, Field(ge=0)] | None = None


class EventAssertion(AssertionBase):
    """An event's count, first time, or order relative to another event."""

    event: EventName
    count: Annotated[int, Field(ge=0)] | CountRange | None = None
    first: TimeOrEnd | None = Field(None, description="The time it first happens.")
    tol: Tolerance = 0.0
    before: EventName | None = Field(None, description="It first happens before this event first happens.")
    after: EventName | None = None

    @model_validator(mode="after")
    def _how(self) -> EventAssertion:
        if self.count is None and self.first is None and self.before is None and self.after is None:
            raise ValueError("expected one of count, first, before, after; found none")
        return self


class SoundAssertion(AssertionBase):
    """A sound started (or stopped) at a time, played for a duration, or a number of times; `tol` applies to
    each time given."""

    sound: Name
    played_at: Seconds | None = Field(None, description="One of its plays started at this time.")
    stopped_at: Seconds | None = Field(None, description="One of its plays stopped at this time.")
    duration: Seconds | None = Field(None, description="Every play lasted this long (start to stop).")
    tol: Tolerance = 0.0
    count: Annotated[int, Field(ge=0)] | CountRange | None = None

    @model_validator(mode="after")
    def _how(self) -> SoundAssertion:
        if all(v is None for v in (self.played_at, self.stopped_at, self.duration, self.count)):
            raise ValueError("expected played_at, stopped_at, duration or count; found none")
        return self


class ContactAssertion(AssertionBase):
    """Two bodies touch (physics contact): at a time, or always / never / eventually over a window."""

    contact: tuple[PartName, PartName]
    at: TimeOrEnd | None = None
    when: Literal["always", "never", "eventually"] | None = None
    during: Window = (0.0, "end")

    @model_validator(mode="after")
    def _how(self) -> ContactAssertion:
        if (self.at is None) == (self.when is None):
            raise ValueError("expected exactly one of `at` or `when` (always, never, eventually)")
        return self


ASSERTION_TAGS: dict[str, type[Strict]] = {
    "value": ValueAssertion,
    "check": CheckAssertion,
    "always": AlwaysAssertion,
    "never": NeverAssertion,
    "eventually": EventuallyAssertion,
    "max": MaxAssertion,
    "min": MinAssertion,
    "becomes": BecomesAssertion,
    "event": EventAssertion,
    "sound": SoundAssertion,
    "contact": ContactAssertion,
}


def _assertion_tag(v: Any) -> str | None:
    if isinstance(v, dict) and "value" in v:
        return "value"  # `value` may come with min/max: it decides the kind
    return tag_of(v, ASSERTION_TAGS)


if TYPE_CHECKING:  # the static view of the tagged union built below from ASSERTION_TAGS
    Assertion = (
        ValueAssertion | CheckAssertion | AlwaysAssertion | NeverAssertion | EventuallyAssertion | MaxAssertion |
        MinAssertion | BecomesAssertion | EventAssertion | SoundAssertion | ContactAssertion
    )
else:
    Assertion = Annotated[
        Union[tuple(Annotated[cls, Tag(tag)] for tag, cls in ASSERTION_TAGS.items())],  # noqa: UP007
        Discriminator(_assertion_tag),
    ]

__all__ = ["ASSERTION_TAGS", "Assertion", "NonNegFloat", "TimeOrEnd", "Window"]
