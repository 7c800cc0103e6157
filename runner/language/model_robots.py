"""Robots of the scenario language: bodies and joints loaded from a URDF or MJCF file (docs/robots.md)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from runner.language.model_base import (
    Expr,
    FiniteFloat,
    NonNegFloat,
    PositiveFloat,
    Strict,
    Surface,
    Vec3,
    finite_vec,
)
from runner.language.model_physics import Drive, Dynamics, Limits, Motor, Rgba

#: A link's or joint's name as the model file spells it (runner.language.model_names): any text without
#: control characters, `"8"` and `pinch site` included.
PartName = Annotated[
    str,
    Field(
        pattern=r"^[^\x00-\x1f\x7f-\x9f]+$",
        max_length=256,
        description="A link's or joint's name as the model file spells it (quote it in YAML if it is a number).",
    ),
]


class Servo(Strict):
    """A position servo, ODE style: each step the velocity motor gets vel = gain x (target - position),
    bounded by fmax (docs/semantics.md, "Position servo")."""

    target: FiniteFloat | Expr = Field(
        description="Target position: radians (hinge) or metres (slider), from the model's zero; a number or an "
        "expression read every step (e.g. `state.q2`)."
    )
    gain: PositiveFloat = Field(description="1/s: the commanded rate per unit of position error.")
    fmax: NonNegFloat = Field(description="Largest torque (N m) or force (N) the servo may use.")
    vmax: PositiveFloat | None = Field(None, description="Largest commanded rate (rad/s or m/s); default none.")


class RobotJoint(Strict):
    """Scenario-level overrides of one joint of a model."""

    motor: Motor | None = Field(None, description="A velocity motor on this joint (replaces the model's none).")
    limits: tuple[FiniteFloat, FiniteFloat] | Limits | None = Field(
        None, description="Stops [lo, hi] from the model's zero (replace the model's own limits)."
    )
    free: bool = Field(False, description="Drop the model's limits (a `continuous` joint).")
    servo: Servo | None = None
    drive: Drive | None = Field(
        None, description="A command: position (PD), velocity (motor) or torque mode (docs/language.md#joint-commands)."
    )
    dynamics: Dynamics | None = Field(
        None, description="Replace the model's damping, friction, armature, effort or velocity limit (each given)."
    )

    @model_validator(mode="after")
    def _check(self) -> RobotJoint:
        if self.servo is not None and self.motor is not None:
            raise ValueError("a joint takes a motor or a servo, not both (the servo drives the motor)")
        if self.drive is not None and (self.servo is not None or self.motor is not None):
            raise ValueError("a joint takes one of motor, servo or drive")
        if self.free and self.limits is not None:
            raise ValueError("`free: true` drops the limits; found limits too")
        if isinstance(self.limits, tuple) and self.limits[0] > self.limits[1]:
            raise ValueError(f"expected limits [lo, hi] with lo <= hi, found {list(self.limits)}")
        if isinstance(self.limits, Limits) and self.limits.zero != "start":
            raise ValueError("a model joint's limits are measured from the model's zero; `zero` is not taken here")
        return self


class ActuatorControl(Strict):
    """The control input of an MJCF `<actuator>` (docs/robots.md, "MJCF actuators")."""

    ctrl: FiniteFloat | Expr = Field(
        description="MuJoCo's `ctrl`: a number or an expression read before every step (clamped to the "
        "actuator's ctrlrange when it has one)."
    )


class RobotLink(Strict):
    """Scenario-level overrides of one link of a model."""

    color: Rgba | None = Field(None, description="RGB or RGBA, 0..1 (replaces the model's colour).")
    surface: Surface | None = Field(None, description="This link's contact surface against every other body.")

    @field_validator("color")
    @classmethod
    def _color(cls, v: Rgba | None) -> Rgba | None:
        if v is not None and not all(0.0 <= c <= 1.0 for c in v):
            raise ValueError(f"expected colour components in 0..1, found {list(v)}")
        return v


class JointStart(Strict):
    """A joint's start: position from the model's zero and rate."""

    pos: FiniteFloat = Field(0.0, description="Radians (hinge) or metres (slider), from the model's zero.")
    vel: FiniteFloat = Field(0.0, description="rad/s or m/s, relative to the parent link.")


class RobotStart(Strict):
    """Where the robot's joints start (default: the model's zero configuration, at rest)."""

    keyframe: PartName | None = Field(
        None, description="An MJCF `<keyframe><key name=...>`: its joint positions and rates (hinges, slides)."
    )
    joints: dict[PartName, FiniteFloat | JointStart] = Field(
        default_factory=dict,
        description="Per joint (hinge or slider): its position, or {pos, vel}; over the keyframe's values.",
    )

    vel: Vec3 = Field(
        (0.0, 0.0, 0.0), description="A free root link's velocity, m/s, world frame (URDF robots not `fixed`)."
    )
    angvel: Vec3 = Field((0.0, 0.0, 0.0), description="A free root link's angular velocity, rad/s, world frame.")

    _v = field_validator("vel", "angvel", mode="before")(finite_vec)

    @property
    def moving_root(self) -> bool:
        return any(self.vel) or any(self.angvel)

    def values(self) -> dict[str, tuple[float, float]]:
        """Joint -> (position, rate) as written here (a keyframe's are the model's)."""
        return {j: (float(v), 0.0) if isinstance(v, float | int) else (v.pos, v.vel) for j, v in self.joints.items()}


class Robot(Strict):
    """Bodies and joints from a URDF or MJCF file: each link is a body `<robot>.<link>`, each joint a joint
    `<robot>.<joint>`, and `<robot>` is the group of all its links."""

    urdf: str | None = Field(
        None,
        description="A URDF file: relative to the scenario, or `@pybullet_data/...` (the models shipped with "
        "pybullet).",
    )
    mjcf: str | None = Field(None, description="An MJCF file (a subset, docs/robots.md), as `urdf`.")
    package_root: str | None = Field(
        None,
        description="Where `package://NAME/...` points: `<package_root>/NAME/...` (as `urdf`); default: looked "
        "for beside the model file, in the folders above it, then on ROS_PACKAGE_PATH. A path that leaves the "
        "root is refused.",
    )
    pos: Vec3 = Field((0.0, 0.0, 0.0), description="Where the model's root frame is placed (world frame).")
    hpr: Vec3 | None = Field(None, description="Heading, pitch, roll of the root frame in degrees.")
    fixed: bool = Field(False, description="Weld the root link to the world (a static body).")
    static_meshes: Literal["hull", "triangles"] = Field(
        "hull",
        description="Meshes of static links: convex hulls (every engine) or the triangles as they are "
        "(`shape:trimesh`).",
    )
    joints: dict[PartName, RobotJoint] = Field(default_factory=dict, description="Overrides per joint of the model.")
    links: dict[PartName, RobotLink] = Field(default_factory=dict, description="Overrides per link of the model.")
    actuators: dict[PartName, ActuatorControl] = Field(
        default_factory=dict,
        description="An MJCF model's actuators driven by name: each one's `ctrl` from the start (docs/robots.md).",
    )
    self_collision: bool | None = Field(
        None,
        description="Whether the model's links touch each other (a joint's two links never do): default off "
        "for URDF (pybullet's default), on for MJCF (MuJoCo's).",
    )
    initial: RobotStart | None = Field(
        None,
        description="The joints' start: positions from the model's zero and rates, or an MJCF keyframe; the links "
        "are placed there and the joints read from the model's zero.",
    )
    exclude: list[tuple[PartName, PartName]] = Field(
        default_factory=list,
        description="Link pairs that never touch, beyond the adjacent ones (a joint's two links never touch).",
    )

    _v = field_validator("pos", "hpr", mode="before")(finite_vec)

    @model_validator(mode="after")
    def _one_file(self) -> Robot:
        given = [k for k in ("urdf", "mjcf") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"expected exactly one of urdf or mjcf, found {', '.join(given) or 'neither'}")
        return self

    @property
    def file(self) -> str:
        return self.urdf if self.urdf is not None else str(self.mjcf)

    @property
    def collides_with_itself(self) -> bool:
        """`self_collision`, or its default for the format (URDF: off, as pybullet; MJCF: on, as MuJoCo)."""
        return self.self_collision if self.self_collision is not None else self.format == "mjcf"

    @property
    def format(self) -> Literal["urdf", "mjcf"]:
        return "urdf" if self.urdf is not None else "mjcf"


__all__ = ["ActuatorControl", "JointStart", "Robot", "RobotJoint", "RobotLink", "RobotStart", "Servo"]
