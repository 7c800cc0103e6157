"""Shared building blocks of the scenario language models."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationInfo, WithJsonSchema, field_validator

from runner.language.times import evaluate_time

SCHEMA_VERSION = 1
#: Every physical number stays within +-MAX_MAGNITUDE (SI units), so that the masses, inertias, poses and
#: step indices computed from them stay finite (docs/reliability.md).
MAX_MAGNITUDE = 1e9

Name = Annotated[
    str,
    Field(
        pattern=r"^[A-Za-z_][A-Za-z0-9_]*$",
        max_length=64,
        description="An identifier: letters, digits and underscores, not starting with a digit.",
    ),
]
#: A body or joint: a hand-written one's name, or a robot's part `<robot>.<link>` / `<robot>.<joint>`.
PartName = Annotated[
    str,
    Field(
        pattern=r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)?$",
        max_length=129,
        description="A body or joint: its name, or a robot's link or joint as `<robot>.<name>`.",
    ),
]
EventName = Annotated[
    str,
    Field(
        pattern=r"^[^\s]+$",
        min_length=1,
        max_length=128,
        description="An event name, Panda3D style: `space`, `mouse1`, `shift-space`, `box-into-door`...",
    ),
]
Expr = Annotated[str, Field(min_length=1, max_length=2000, description="An expression (docs/language.md#expressions).")]
PositiveFloat = Annotated[float, Field(gt=0, le=MAX_MAGNITUDE, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE, allow_inf_nan=False)]
NonNegFloat = Annotated[float, Field(ge=0, le=MAX_MAGNITUDE, allow_inf_nan=False)]
Vec3 = tuple[FiniteFloat, FiniteFloat, FiniteFloat]
Quat = tuple[FiniteFloat, FiniteFloat, FiniteFloat, FiniteFloat]


class Strict(BaseModel):
    """Base of every model: unknown keys are refused, values are checked as given.

    The validators are built when first used (``defer_build``), not as each class is made: validating a
    scenario builds the schemas of the models it reaches once, inside :class:`~runner.language.model.Scenario`'s,
    instead of each model's own validator at import and then the whole tree again (about 15 ms of every
    command's start-up). The schemas, the JSON schema and the error messages are the same."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True, defer_build=True)


def finite_vec(v: Any) -> Any:
    if isinstance(v, list | tuple) and any(isinstance(c, float) and not math.isfinite(c) for c in v):
        raise ValueError("expected finite numbers, found NaN or infinity")
    return v


def _time(value: Any, info: ValidationInfo) -> Any:
    """A time written as an expression becomes its value (runner.language.times); `end` stays as it is."""
    if isinstance(value, str) and value != "end":
        return evaluate_time(value, info.context)
    return value


_TIME_TEXT = {
    "type": "string",
    "minLength": 1,
    "description": "An expression of params and constants (param.<name>, dt, duration, g, gravity.x|y|z, pi), "
    "evaluated once when the scenario is loaded.",
}


def _time_schema(minimum: str, end: bool = False) -> WithJsonSchema:
    number: dict[str, Any] = {"type": "number", minimum: 0, "maximum": MAX_MAGNITUDE}
    options: list[dict[str, Any]] = [number, _TIME_TEXT] + ([{"const": "end"}] if end else [])
    return WithJsonSchema({"anyOf": options})


#: Seconds >= 0: a number or an expression evaluated at load (docs/language.md, "Times").
Seconds = Annotated[
    float, Field(ge=0, le=MAX_MAGNITUDE, allow_inf_nan=False), BeforeValidator(_time), _time_schema("minimum")
]
#: Seconds > 0, as :data:`Seconds`.
PositiveSeconds = Annotated[
    float, Field(gt=0, le=MAX_MAGNITUDE, allow_inf_nan=False), BeforeValidator(_time), _time_schema("exclusiveMinimum")
]
#: Seconds >= 0 or `end` (the run's last step), as :data:`Seconds`.
TimeOrEnd = Annotated[
    Annotated[float, Field(ge=0, le=MAX_MAGNITUDE, allow_inf_nan=False)] | Literal["end"],
    BeforeValidator(_time),
    _time_schema("minimum", end=True),
]
#: A window [start, end] of times (either may be `end`).
Window = tuple[TimeOrEnd, TimeOrEnd]


class Surface(Strict):
    """An ODE contact surface."""

    bounce: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = Field(
        0.0, description="Restitution (ODE bounce), 0..1."
    )
    bounce_vel: NonNegFloat = Field(0.0, description="Minimum approach speed for a bounce, m/s (ODE bounce_vel).")
    mu: Annotated[float, Field(ge=0)] = Field(
        math.inf, description="Coulomb friction coefficient; `inf` for no slip (ODE dInfinity)."
    )

    @field_validator("mu")
    @classmethod
    def _mu_not_nan(cls, v: float) -> float:
        if math.isnan(v):
            raise ValueError("expected a number >= 0 or inf, found NaN")
        return v
