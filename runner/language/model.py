"""The scenario document: the root of the language (schema version 1)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from runner.language.model_actions import Action, IntervalId, StateValue
from runner.language.model_assertions import Assertion
from runner.language.model_base import SCHEMA_VERSION, EventName, Name, Strict, Surface
from runner.language.model_behaviour import Collisions, Handler, Input, IntervalDef, Trigger
from runner.language.model_physics import Body, Joint, PairSurface, World
from runner.language.model_robots import Robot

#: A body, a group or a robot's link (`arm.link_3`).
BodyRef = Annotated[
    str,
    Field(
        pattern=r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)?$",
        max_length=129,
        description="A body, a group, or a robot's link as `<robot>.<link>`.",
    ),
]

#: A scenario's and a variant's names make a trace's file name `<scenario>__<variant>__<backend>.mcap.partial`:
#: 128 + 64 characters keep it (and the `.cost.json.partial` beside it) under the 255 bytes of a file name.
MAX_SCENARIO_NAME = 128
MAX_VARIANT_NAME = 64


VariantName = Annotated[str, Field(pattern=r"^[A-Za-z0-9_.-]+$", max_length=MAX_VARIANT_NAME)]


class TraceOptions(Strict):
    """What the trace records beyond every body, joint and contact pair (docs/trace-format.md)."""

    contact_points: bool = Field(
        False,
        description="Record each step's contact points on /contact_points: one arrow per point, at the point, "
        "along the force on the second body, as long as its normal force times `contact_arrow_scale` (needs "
        "a backend with `contacts:points`; reading points costs time).",
    )
    contact_arrow_scale: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = Field(
        None,
        description="Metres of arrow per newton (default: the heaviest moving body's weight is 0.25 m long).",
    )


class Variant(Strict):
    """A named case: overrides applied to the base scenario."""

    description: str | None = Field(None, max_length=2000)
    set: dict[str, Any] = Field(
        default_factory=dict,
        description="Dotted paths to replace, e.g. `world.duration: 10` or `bodies.door.pos: [0, 0, 1]`.",
    )
    inputs: list[Input] | None = Field(None, description="Replaces the base timeline when given.")
    assertions: list[Assertion] = Field(default_factory=list, description="Added to the base assertions.")


class Scenario(Strict):
    schema_version: Literal[1] = Field(description=f"The language version; this runner reads {SCHEMA_VERSION}.")
    scenario: Annotated[str, Field(min_length=1, max_length=MAX_SCENARIO_NAME, pattern=r"^[A-Za-z0-9_.-]+$")] = Field(
        description="The scenario's name."
    )
    description: str | None = Field(None, max_length=5000)
    params: dict[Name, StateValue] = Field(
        default_factory=dict,
        description="Values substituted for `${name}` anywhere, readable as `param.name`; set with --set.",
    )
    world: World
    surface: Surface = Field(default_factory=Surface, description="The default contact surface.")
    surfaces: list[PairSurface] = Field(default_factory=list, description="Overrides per body pair.")
    bodies: dict[Name, Body] = Field(
        default_factory=dict,
        description="Hand-written bodies, by name; may be left out when `robots` bring every body.",
    )
    joints: dict[Name, Joint] = Field(default_factory=dict)
    robots: dict[Name, Robot] = Field(
        default_factory=dict, description="Models loaded from URDF or MJCF files (docs/robots.md)."
    )
    exclude_contacts: list[tuple[BodyRef, BodyRef]] = Field(
        default_factory=list,
        description="Pairs of bodies (or groups, or robot links `<robot>.<link>`) that never touch.",
    )
    sounds: dict[Name, str] = Field(default_factory=dict, description="WAV files, relative to the scenario.")
    state: dict[Name, StateValue] = Field(default_factory=dict, description="State variables and initial values.")
    collisions: Collisions = Field(default_factory=Collisions)
    intervals: dict[IntervalId, IntervalDef] = Field(default_factory=dict)
    triggers: dict[EventName, Trigger] = Field(
        default_factory=dict,
        description="Events raised when a condition becomes true: event name -> {when, once}.",
    )
    on: dict[EventName, list[Action] | Handler] = Field(
        default_factory=dict,
        description="Event handlers: event -> [actions], or {do: [actions], once, min_interval}. "
        "`start` is sent before the first step.",
    )
    inputs: list[Input] = Field(default_factory=list, description="Timed input events.")
    assertions: list[Assertion] = Field(default_factory=list)
    variants: dict[VariantName, Variant] = Field(
        default_factory=dict, description="Named cases (names: letters, digits, `_ . -`; part of trace file names)."
    )
    backend_options: dict[Name, dict[str, Any]] = Field(
        default_factory=dict, description="Per-backend engine options (see `scenario backends`)."
    )
    trace: TraceOptions = Field(default_factory=TraceOptions, description="What the trace records (optional).")
