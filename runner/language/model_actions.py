"""The actions a handler, a trigger or an interval's `func` runs (start, set, motor, drive, apply, if...), the
commands they carry, and the tagged union that reads them."""

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
    PositiveSeconds,
    Quat,
    Strict,
    Vec3,
    finite_vec,
)
from runner.language.model_physics import Drive

IntervalId = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_-]*$", max_length=64)]
#: A state variable's or a parameter's value; an integer beyond 2**53 becomes a float, as in expressions.
StateValue = Annotated[bool | int | float | str, AfterValidator(bounded)]


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
# IfAction's `Action` is resolved from this module when its validator is first built (Strict: defer_build)


__all__ = [
    "ACTION_TAGS",
    "Action",
    "IntervalId",
    "StateValue",
    "tag_of",
    "ApplyAction",
    "ApplyCommand",
    "CalcAction",
    "ControlAction",
    "ControlCommand",
    "DriveAction",
    "DriveCommand",
    "EndAction",
    "FinishAction",
    "ForceAction",
    "ForceCommand",
    "IfAction",
    "ImpulseAction",
    "LogAction",
    "LogCommand",
    "LoopAction",
    "MotorAction",
    "MotorCommand",
    "PauseAction",
    "PlaySoundAction",
    "ResetAction",
    "ResetCommand",
    "ResumeAction",
    "SendAction",
    "SetAction",
    "StartAction",
    "StopSoundAction",
]
