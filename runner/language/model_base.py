"""Shared building blocks of the scenario language models."""

from __future__ import annotations

import math
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, field_validator

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
    """Base of every model: unknown keys are refused, values are checked as given."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)


def finite_vec(v: Any) -> Any:
    if isinstance(v, list | tuple) and any(isinstance(c, float) and not math.isfinite(c) for c in v):
        raise ValueError("expected finite numbers, found NaN or infinity")
    return v


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


TimeOrEnd = float | str  # "end" or seconds


def check_time_or_end(v: Any) -> Any:
    if isinstance(v, str) and v != "end":
        raise ValueError(f"expected a time in seconds or `end`, found {v!r}")
    if isinstance(v, float) and (not math.isfinite(v) or v < 0):
        raise ValueError(f"expected a time >= 0, found {v}")
    return v
