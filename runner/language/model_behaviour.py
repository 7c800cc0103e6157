"""Sounds, collision solids, intervals, actions, handlers and timed inputs."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal, Union

from pydantic import AfterValidator, Discriminator, Field, Tag, field_validator, model_validator

from runner.language.expression_values import bounded
from runner.language.model_base import (
    EventName,
    Expr,
    FiniteFloat,
    Name,
    NonNegFloat,
    PartName,
    PositiveFloat,
    PositiveSeconds,
    Quat,
    Seconds,
    Strict,
    Vec3,
    finite_vec,
)
from runner.language.model_physics import Drive

IntervalId = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_-]*$", max_length=64)]
Blend = Literal["noBlend", "easeIn", "easeOut", "easeInOut"]
#: A state variable's or a parameter's value; an integer beyond 2**53 becomes a float, as in expressions.
StateValue = Annotated[bool | int | float | str, AfterValidator(bounded)]


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


# --- actions --------------------------------------------------------------------------------------
class MotorCommand(Strict):
    joint: PartName
    vel: FiniteFloat
    fmax: NonNegFloat | None = Field(None, description="Unchanged when omitted.")


class DriveCommand(Drive):
    """A joint's command from now on (docs/language.md#joint-commands): position, velocity or torque mode."""

    joint: PartName


class ControlCommand(Strict):
    """An MJCF actuator's control input from now on (docs/robots.md, "MJCF actuators")."""

    actuator: PartName = Field(description="`<robot>.<actuator>`, the actuator's name in the MJCF file.")
    ctrl: FiniteFloat | Expr = Field(description="A number or an expression read before every step.")


class ForceCommand(Strict):
    body: PartName
    value: Vec3 = Field(description="World frame, at the centre of mass (N, or N s for an impulse).")
    torque: Vec3 = Field((0.0, 0.0, 0.0), description="World frame (N m, or N m s for an impulse).")

    _v = field_validator("value", "torque", mode="before")(finite_vec)


class ResetCommand(Strict):
    body: PartName
    pos: Vec3 | None = Field(None, description="Default: the body's start position.")
    hpr: Vec3 | None = None
    quat: Quat | None = None
    vel: Vec3 = (0.0, 0.0, 0.0)
    angvel: Vec3 = (0.0, 0.0, 0.0)

    _v = field_validator("pos", "hpr", "quat", "vel", "angvel", mode="before")(finite_vec)


class ApplyCommand(Strict):
    """A force and/or torque held on a body for a while: applied on every step (and every substep) from the
    step the action runs in, for `for` seconds or until `until` holds (docs/semantics.md, "Held forces")."""

    body: PartName
    force: Vec3 = Field((0.0, 0.0, 0.0), description="N, in `frame`, acting at `at`.")
    torque: Vec3 = Field((0.0, 0.0, 0.0), description="N m, in `frame`.")
    frame: Literal["world", "body"] = Field(
        "world", description="`body`: the vectors turn with the body (read at the start of each step)."
    )
    at: Vec3 | None = Field(
        None, description="Where the force acts: a point in the body frame; default the centre of mass."
    )
    for_: PositiveSeconds | None = Field(
        None, alias="for", description="How long: seconds, rounded to whole steps (at least one)."
    )
    until: Expr | None = Field(
        None, description="A condition checked before each step: the force stops at the first step it holds."
    )

    _v = field_validator("force", "torque", "at", mode="before")(finite_vec)

    @model_validator(mode="after")
    def _one_end(self) -> ApplyCommand:
        if (self.for_ is None) == (self.until is None):
            raise ValueError("expected exactly one of `for` (seconds) or `until` (a condition)")
        return self


class LogCommand(Strict):
    message: str = Field(max_length=2000)
    level: Literal["debug", "info", "warning", "error"] = "info"


class StartAction(Strict):
    start: IntervalId


class PauseAction(Strict):
    pause: IntervalId


class ResumeAction(Strict):
    resume: IntervalId


class FinishAction(Strict):
    finish: IntervalId


class LoopAction(Strict):
    loop: IntervalId


class SetAction(Strict):
    set: dict[Name, StateValue] = Field(description="State variables to set to constants.")


class CalcAction(Strict):
    calc: dict[Name, Expr] = Field(description="State variables to set to the value of an expression.")


class PlaySoundAction(Strict):
    play_sound: Name


class StopSoundAction(Strict):
    stop_sound: Name


class MotorAction(Strict):
    motor: MotorCommand


class DriveAction(Strict):
    drive: DriveCommand


class ControlAction(Strict):
    control: ControlCommand


class ForceAction(Strict):
    force: ForceCommand


class ImpulseAction(Strict):
    impulse: ForceCommand


class ApplyAction(Strict):
    apply: ApplyCommand


class ResetAction(Strict):
    reset: PartName | ResetCommand


class LogAction(Strict):
    log: str | LogCommand


class SendAction(Strict):
    send: EventName


class EndAction(Strict):
    end: bool | str = Field(description="`true`, or the reason to log.")


class IfAction(Strict):
    if_: Expr = Field(alias="if")
    then: list[Action] = Field(default_factory=list)
    else_: list[Action] = Field(default_factory=list, alias="else")


ACTION_TAGS: dict[str, type[Strict]] = {
    "start": StartAction,
    "pause": PauseAction,
    "resume": ResumeAction,
    "finish": FinishAction,
    "loop": LoopAction,
    "set": SetAction,
    "calc": CalcAction,
    "play_sound": PlaySoundAction,
    "stop_sound": StopSoundAction,
    "motor": MotorAction,
    "drive": DriveAction,
    "control": ControlAction,
    "force": ForceAction,
    "impulse": ImpulseAction,
    "apply": ApplyAction,
    "reset": ResetAction,
    "log": LogAction,
    "send": SendAction,
    "end": EndAction,
    "if": IfAction,
}


def tag_of(value: Any, tags: dict[str, type[Strict]]) -> str | None:
    """The tag of a union member: the first key naming a kind (dict input) or the model's kind."""
    if isinstance(value, dict):
        return next((k for k in value if k in tags), None)
    return next((k for k, cls in tags.items() if isinstance(value, cls)), None)


if TYPE_CHECKING:  # the static view of the tagged union built below from ACTION_TAGS
    Action = (
        StartAction | PauseAction | ResumeAction | FinishAction | LoopAction | SetAction | CalcAction |
        PlaySoundAction | StopSoundAction | MotorAction | DriveAction | ControlAction | ForceAction | ImpulseAction |
        ApplyAction | ResetAction | LogAction | SendAction | EndAction | IfAction
    )
else:
    Action = Annotated[
        Union[tuple(Annotated[cls, Tag(tag)] for tag, cls in ACTION_TAGS.items())],  # noqa: UP007
        Discriminator(lambda v: tag_of(v, ACTION_TAGS)),
    ]
IfAction.model_rebuild()


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
    "ACTION_TAGS",
    "Action",
    "Collisions",
    "Handler",
    "Input",
    "IntervalDef",
    "Step",
    "Trigger",
    "handler_parts",
    "tag_of",
]
