"""Collision solids, intervals, timed inputs, handlers and condition triggers; the actions they run are in
:mod:`runner.language.model_actions`."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from runner.language.model_actions import Action, IntervalId
from runner.language.model_base import (
    EventName,
    Expr,
    Name,
    PositiveFloat,
    PositiveSeconds,
    Seconds,
    Strict,
    Vec3,
)

Blend = Literal["noBlend", "easeIn", "easeOut", "easeInOut"]


# --- collision solids (Panda3D CollisionNode / CollisionHandlerEvent) --------------------------------
class SphereSolid(Strict):
    center: Vec3 = (0.0, 0.0, 0.0)
    radius: PositiveFloat


class BoxSolid(Strict):
    center: Vec3 = (0.0, 0.0, 0.0)
    size: Vec3 = Field(description="Full edge lengths in the body frame, before scale.")


class Solid(Strict):
    sphere: SphereSolid | None = None
    polygon: list[Vec3] | None = Field(None, description="Vertices, counter-clockwise seen from the normal side.")
    box: BoxSolid | None = None

    @model_validator(mode="after")
    def _one(self) -> Solid:
        kinds = [k for k in ("sphere", "polygon", "box") if getattr(self, k) is not None]
        if len(kinds) != 1:
            raise ValueError(f"expected exactly one of sphere, polygon, box; found {', '.join(kinds) or 'none'}")
        return self


class CollisionNode(Strict):
    body: Name
    solids: list[Solid] = Field(default_factory=list)
    sphere: SphereSolid | None = Field(None, description="Shorthand for one sphere solid.")
    polygon: list[Vec3] | None = Field(None, description="Shorthand for one polygon solid.")
    box: BoxSolid | None = Field(None, description="Shorthand for one box solid.")

    def all_solids(self) -> list[Solid]:
        extra = [Solid(**{k: getattr(self, k)}) for k in ("sphere", "polygon", "box") if getattr(self, k) is not None]
        return [*self.solids, *extra]

    @model_validator(mode="after")
    def _some(self) -> CollisionNode:
        if not self.all_solids():
            raise ValueError("expected at least one solid (sphere, polygon or box), found none")
        return self


class Collisions(Strict):
    nodes: dict[Name, CollisionNode] = Field(default_factory=dict)
    from_: list[Name] = Field(
        default_factory=list, alias="from", description="Collision nodes that are colliders (Panda3D addCollider)."
    )
    contacts_from: list[Name] = Field(
        default_factory=list, description="Bodies whose physics contacts also raise in/again/out events."
    )
    in_: list[str] = Field(["%fn-into-%in"], alias="in", description="In patterns (%fn, %in, %fs, %is, %ig).")
    again: list[str] = Field(default_factory=list, description="Again patterns.")
    out: list[str] = Field(default_factory=list, description="Out patterns.")


# --- intervals ------------------------------------------------------------------------------------
class Lerp(Strict):
    body: Name
    duration: Seconds
    blend: Blend = "noBlend"
    pos: Vec3 | None = None
    hpr: Vec3 | None = Field(None, description="Degrees, per component, no wrap.")
    scale: PositiveFloat | None = None
    start_pos: Vec3 | None = Field(None, description="Default: captured at the interval's first step.")
    start_hpr: Vec3 | None = None
    start_scale: PositiveFloat | None = None

    @model_validator(mode="after")
    def _some(self) -> Lerp:
        if self.pos is None and self.hpr is None and self.scale is None:
            raise ValueError("expected at least one of pos, hpr, scale to lerp to, found none")
        for name in ("pos", "hpr", "scale"):
            if getattr(self, f"start_{name}") is not None and getattr(self, name) is None:
                raise ValueError(f"`start_{name}` is given without `{name}` (a start needs an end to lerp to)")
        return self


class SoundStep(Strict):
    sound: Name
    duration: PositiveSeconds | None = Field(None, description="Default: the sound's length minus start_time.")
    volume: Annotated[float, Field(ge=0, le=1)] = 1.0
    loop: bool = False
    start_time: Seconds = 0.0


class Step(Strict):
    """One interval: exactly one of lerp, sequence, parallel, wait, sound, func, interval."""

    lerp: Lerp | None = None
    sequence: list[Step] | None = None
    parallel: list[Step] | None = None
    wait: Seconds | None = None
    sound: Name | SoundStep | None = None
    func: list[Action] | None = Field(None, description="An action step (Panda3D Func): actions run at once.")
    interval: IntervalId | None = Field(None, description="Another named interval, inlined here.")
    duration: PositiveSeconds | None = Field(
        None, description="Sequence/parallel only: a fixed ('phony') duration."
    )

    @model_validator(mode="after")
    def _one(self) -> Step:
        kinds = [
            k
            for k in ("lerp", "sequence", "parallel", "wait", "sound", "func", "interval")
            if getattr(self, k) is not None
        ]
        if len(kinds) != 1:
            raise ValueError(
                "expected exactly one of lerp, sequence, parallel, wait, sound, func, interval; "
                f"found {', '.join(kinds) or 'none'}"
            )
        if self.duration is not None and kinds[0] not in ("sequence", "parallel"):
            raise ValueError(f"`duration` belongs to sequence or parallel, not {kinds[0]}")
        return self


class IntervalDef(Step):
    name: str | None = Field(
        None,
        max_length=128,
        description="The Panda3D name. Starting an interval whose "
        "name is playing finishes the old one first (same-name takeover). Default: the id.",
    )


# --- timed inputs ---------------------------------------------------------------------------------
class Repeat(Strict):
    every: PositiveSeconds
    count: Annotated[int, Field(ge=1, le=100_000)]


class Input(Strict):
    at: Seconds = Field(description="Simulated time in seconds (a number or an expression of params).")
    event: EventName
    repeat: Repeat | None = None


# --- handlers and condition triggers --------------------------------------------------------------
class Handler(Strict):
    """A handler with options: the actions under `do`, run at most once, or not again within `min_interval`."""

    do: list[Action] = Field(description="The actions, as in the short form `event: [actions]`.")
    once: bool = Field(False, description="Run only for the event's first delivery (Panda3D's acceptOnce).")
    min_interval: Seconds | None = Field(
        None,
        description="Skip deliveries less than this many seconds after the last one the handler ran for "
        "(chattering contacts); the events still happen and count.",
    )

    @model_validator(mode="after")
    def _one_rule(self) -> Handler:
        if self.once and self.min_interval is not None:
            raise ValueError("expected `once` or `min_interval`, found both")
        return self


class Trigger(Strict):
    """An event raised when a condition becomes true (edge-triggered), checked after every step."""

    when: Expr = Field(description="A condition (docs/language.md#expressions).")
    once: bool = Field(
        False, description="Raise the event only the first time; by default it is re-armed when the condition "
        "becomes false again.",
    )
    description: str | None = Field(None, max_length=2000)


def handler_parts(handler: list[Any] | Handler) -> tuple[list[Any], bool, float | None]:
    """(actions, once, min_interval) of a handler written either way."""
    if isinstance(handler, Handler):
        return handler.do, handler.once, handler.min_interval
    return handler, False, None


__all__ = [
    "Collisions",
    "Handler",
    "Input",
    "IntervalDef",
    "Step",
    "Trigger",
    "handler_parts",
]
