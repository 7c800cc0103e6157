"""World, bodies, joints and surfaces of the scenario language."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from runner.language.model_base import (
    Expr,
    FiniteFloat,
    Name,
    NonNegFloat,
    PositiveFloat,
    Quat,
    Strict,
    Surface,
    Vec3,
    finite_vec,
)
from runner.language.model_inertia import Inertia, moments_list_schema


class FluidMedium(Strict):
    """MuJoCo's inertia-box fluid model (docs/semantics.md, "Fluid forces"): every dynamic body with mass is
    dragged by it, on every engine."""

    density: NonNegFloat = Field(0.0, description="kg/m^3: quadratic drag (air 1.2, water 1000).")
    viscosity: NonNegFloat = Field(0.0, description="Pa s: linear (Stokes) drag (air 1.8e-5, water 1e-3).")
    wind: Vec3 = Field((0.0, 0.0, 0.0), description="m/s, world frame: the fluid's velocity.")

    _v = field_validator("wind", mode="before")(finite_vec)


class World(Strict):
    gravity: Vec3 = Field((0.0, 0.0, -9.81), description="m/s^2, world frame (Z up).")
    dt: PositiveFloat = Field(description="The scenario step in seconds (the lab uses 0.04).")
    duration: PositiveFloat = Field(description="Simulated seconds to run.")
    substeps: Annotated[int, Field(ge=1, le=1000)] = Field(1, description="Physics steps per scenario step.")
    options: Literal["scenario", "model"] = Field(
        "scenario",
        description="`model`: an MJCF robot's own `<option>` rules (its step, gravity, integrator, solver and "
        "its geoms' contact parameters; MuJoCo steps it with its own mj_step), as MuJoCo runs the file; `dt` / "
        "`substeps` and `gravity` must equal the model's (docs/robots.md). `scenario`: the scenario's "
        "semantics (ODE's), the default.",
    )
    fluid: FluidMedium | None = Field(
        None,
        description="The fluid every dynamic body is in (MuJoCo's inertia-box model, on every engine); it "
        "replaces an MJCF robot's `<option density viscosity wind>`. Default: the MJCF robot's, else none.",
    )
    budget: PositiveFloat | None = Field(
        None,
        description="Wall-clock seconds a run may take, building the world included (default: the command's "
        "limit, 3600 s for `run`); `--timeout` overrides it. A run whose cost per step says it would take longer "
        "is stopped early, naming that cost (exit 3).",
    )

    _v = field_validator("gravity", mode="before")(finite_vec)


class Cylinder(Strict):
    radius: PositiveFloat
    length: PositiveFloat = Field(description="Length of the cylindrical part, along the body's local z.")


class Plane(Strict):
    """An infinite static plane through the body's position, normal along its local +z."""


class BodyArray(Strict):
    """Copies of a body named `<name>_0` ... `<name>_<n-1>`; the plain name refers to the whole group."""

    count: Annotated[int, Field(ge=1, le=10_000)] | tuple[int, int, int] = Field(
        description="How many copies: n (a column along z) or [nx, ny, nz]."
    )
    spacing: Vec3 = Field((0.0, 0.0, 1.0), description="Offset between neighbours along x, y, z (metres).")
    layer_shift: Vec3 = Field((0.0, 0.0, 0.0), description="Extra offset added per layer (z index).")

    @field_validator("count")
    @classmethod
    def _count(cls, v: int | tuple[int, int, int]) -> int | tuple[int, int, int]:
        if isinstance(v, tuple) and (min(v) < 1 or v[0] * v[1] * v[2] > 10_000):
            raise ValueError(f"expected counts >= 1 with at most 10000 copies in all, found {list(v)}")
        return v


Rgba = tuple[float, float, float] | tuple[float, float, float, float]


class Body(Strict):
    box: Vec3 | None = Field(None, description="Full edge lengths (x, y, z), before scale.")
    sphere: PositiveFloat | None = Field(None, description="Radius, before scale.")
    capsule: Cylinder | None = None
    cylinder: Cylinder | None = None
    plane: Plane | None = None
    motion: Literal["dynamic", "kinematic", "static"] = Field(
        "dynamic",
        description="dynamic: simulated; kinematic: moved by intervals and actions, carries what "
        "rests on it; static: never moves.",
    )
    mass: PositiveFloat | None = Field(None, description="kg; inertia from the shape (ODE dMassSet*Total).")
    density: PositiveFloat | None = Field(None, description="kg/m^3; mass = density x volume (ODE dMassSet*).")
    inertia: Inertia | None = Field(
        None,
        description="kg m^2 about the centre of mass, instead of the shape's: principal moments along the body's "
        "axes `[Ixx, Iyy, Izz]`, `{moments: [I1, I2, I3], quat | hpr}` along turned axes, or the full tensor "
        "`{ixx, iyy, izz, ixy, ixz, iyz}` in the body frame; positive definite, with each principal moment at most "
        "the sum of the other two. Dynamic bodies only.",
        json_schema_extra=moments_list_schema,
    )
    pos: Vec3 = (0.0, 0.0, 0.0)
    hpr: Vec3 | None = Field(None, description="Heading, pitch, roll in degrees, Panda3D's convention.")
    quat: Quat | None = Field(None, description="Orientation as (w, x, y, z).")
    scale: PositiveFloat = Field(1.0, description="Uniform scale of the shape and its collision solids.")
    vel: Vec3 = Field((0.0, 0.0, 0.0), description="Initial linear velocity, m/s.")
    angvel: Vec3 = Field((0.0, 0.0, 0.0), description="Initial angular velocity, rad/s, world frame.")
    color: Rgba | None = Field(None, description="RGB or RGBA, 0..1, for the 3D view.")
    array: BodyArray | None = None

    _v = field_validator("pos", "vel", "angvel", "hpr", "quat", "box", mode="before")(finite_vec)

    @model_validator(mode="after")
    def _one_shape(self) -> Body:
        shapes = [k for k in ("box", "sphere", "capsule", "cylinder", "plane") if getattr(self, k) is not None]
        if len(shapes) != 1:
            found = ", ".join(shapes) if shapes else "none"
            raise ValueError(f"expected exactly one shape (box, sphere, capsule, cylinder or plane), found {found}")
        if self.box is not None and min(self.box) <= 0:
            raise ValueError(f"expected box sizes > 0, found {list(self.box)}")
        if self.hpr is not None and self.quat is not None:
            raise ValueError("expected either hpr or quat, found both")
        if self.quat is not None and sum(c * c for c in self.quat) < 1e-12:
            raise ValueError("expected a non-zero quaternion, found (0, 0, 0, 0)")
        if self.mass is not None and self.density is not None:
            raise ValueError("expected either mass or density, found both")
        if self.plane is not None and self.motion != "static":
            raise ValueError(f"a plane must be static, found motion: {self.motion}")
        if self.motion == "dynamic" and self.mass is None and self.density is None:
            raise ValueError("a dynamic body needs mass or density, found neither")
        if self.inertia is not None and self.motion != "dynamic":
            raise ValueError(f"`inertia` is for dynamic bodies, found motion: {self.motion}")
        if self.color is not None and not all(0.0 <= c <= 1.0 for c in self.color):
            raise ValueError(f"expected colour components in 0..1, found {list(self.color)}")
        return self


class Motor(Strict):
    vel: FiniteFloat = Field(0.0, description="Target rate: m/s (slider) or rad/s (hinge) (ODE dParamVel).")
    fmax: NonNegFloat = Field(
        description="Largest force (N) or torque (N m) the motor may use; 0 = off (ODE dParamFMax)."
    )


class Drive(Strict):
    """A joint command in one of three modes (docs/semantics.md, "Joint commands"): exactly one of `position`
    (a PD law applied as a torque), `vel` (the velocity motor, ODE's dParamVel/dParamFMax) or `torque`."""

    position: FiniteFloat | Expr | None = Field(
        None,
        description="Position mode: the target, radians (hinge) or metres (slider) from the joint's zero; a "
        "number or an expression read before every step (e.g. `0.5*sin(time)`). The joint gets the torque "
        "kp (position - q) + kd (rate - qdot), capped by its effort limit.",
    )
    rate: FiniteFloat | Expr = Field(
        0.0, description="Position mode: the target rate (rad/s or m/s), a number or an expression; default 0."
    )
    kp: NonNegFloat | None = Field(None, description="Position mode: stiffness, N m/rad (hinge) or N/m (slider).")
    kd: NonNegFloat = Field(0.0, description="Position mode: damping, N m s/rad (hinge) or N s/m (slider).")
    vel: FiniteFloat | None = Field(None, description="Velocity mode: the motor's target rate (ODE dParamVel).")
    fmax: NonNegFloat | None = Field(
        None, description="Velocity mode: the largest force or torque the motor may use (ODE dParamFMax)."
    )
    torque: FiniteFloat | Expr | None = Field(
        None,
        description="Torque mode: the torque (N m, hinge) or force (N, slider), held until changed; a number or "
        "an expression read before every step. Equal and opposite on the joint's two bodies.",
    )

    @property
    def mode(self) -> Literal["position", "velocity", "torque"]:
        if self.position is not None:
            return "position"
        return "velocity" if self.vel is not None else "torque"

    @model_validator(mode="after")
    def _one_mode(self) -> Drive:
        modes = [k for k in ("position", "vel", "torque") if getattr(self, k) is not None]
        if len(modes) != 1:
            raise ValueError(f"expected exactly one of position, vel, torque; found {', '.join(modes) or 'none'}")
        if self.position is not None and self.kp is None:
            raise ValueError("position mode needs `kp` (N m/rad or N/m)")
        if self.position is None and ("kp" in self.model_fields_set or "kd" in self.model_fields_set
                                      or "rate" in self.model_fields_set):  # fmt: skip
            raise ValueError("`kp`, `kd` and `rate` belong to position mode (`position: TARGET`)")
        if self.vel is not None and self.fmax is None:
            raise ValueError("velocity mode needs `fmax` (N or N m; 0 = off)")
        if self.vel is None and self.fmax is not None:
            raise ValueError("`fmax` belongs to velocity mode (`vel: RATE`)")
        return self


class Limits(Strict):
    """Stops on a slider or hinge coordinate, with a stated zero and (optionally) a bouncy or soft stop."""

    lo: FiniteFloat = Field(description="Low stop: metres (slider) or radians (hinge), from `zero`.")
    hi: FiniteFloat = Field(description="High stop, as lo.")
    zero: Literal["start", "absolute"] = Field(
        "start",
        description="Where the coordinate is 0: `start` (the start pose) or `absolute` (hinge: the body's "
        "orientation equal to the other's; slider: the body's origin at `anchor`, by default the other body's "
        "origin or the world origin). `<joint>.position` reads from the same zero.",
    )
    bounce: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = Field(
        0.0, description="Restitution of the stops, 0..1 (ODE dParamBounce)."
    )
    stiffness: PositiveFloat | None = Field(
        None, description="A soft stop: spring stiffness, N/m or N m/rad (ODE dParamStopERP/CFM); default rigid."
    )
    damping: NonNegFloat | None = Field(
        None, description="A soft stop: damping, N s/m or N m s/rad (with stiffness; default 0)."
    )

    @model_validator(mode="after")
    def _check(self) -> Limits:
        if self.lo > self.hi:
            raise ValueError(f"expected lo <= hi, found lo {self.lo} and hi {self.hi}")
        if self.damping is not None and self.stiffness is None:
            raise ValueError("a soft stop needs `stiffness` (damping alone is not a stop)")
        return self


class Dynamics(Strict):
    """A slider's or hinge's own dynamics (docs/semantics.md, "Joint dynamics"). On a model's joint each
    field given replaces the model's value (URDF `<dynamics>`/`<limit>`, MJCF's joint); one left out keeps
    it."""

    damping: NonNegFloat | None = Field(
        None, description="Viscous damping: a force -damping x rate, N s/m (slider) or N m s/rad (hinge)."
    )
    friction: NonNegFloat | None = Field(
        None,
        description="Dry joint friction (MuJoCo's frictionloss, URDF's `friction`): the joint is held still "
        "by up to this force (N) or torque (N m), and slides against it.",
    )
    armature: NonNegFloat | None = Field(
        None,
        description="Inertia added to the coordinate (a rotor's reflected inertia), kg (slider) or kg m^2 "
        "(hinge), on the engines that declare `joint:armature` (MuJoCo, PyBullet, DART, Drake, ODE).",
    )
    effort: PositiveFloat | None = Field(
        None,
        description="The largest force (N) or torque (N m) a motor, servo, drive or MJCF actuator may apply: caps "
        "fmax and the commanded torque.",
    )
    velocity: PositiveFloat | None = Field(
        None, description="The largest rate (m/s or rad/s) a motor or servo may command: caps its vel."
    )


class Joint(Strict):
    type: Literal["slider", "hinge", "ball", "fixed", "universal"]
    bodies: tuple[Name, Name] = Field(description="[body, other]; other may be `environment`.")
    axis: Vec3 = Field((1.0, 0.0, 0.0), description="World-frame axis at the start (slider, hinge, universal).")
    axis2: Vec3 | None = Field(None, description="Second axis of a universal joint.")
    anchor: Vec3 | None = Field(None, description="World-frame anchor; default: the first body's position.")
    limits: tuple[FiniteFloat, FiniteFloat] | Limits | None = Field(
        None,
        description="Stops: [lo, hi] in metres (slider) or radians (hinge) from the start pose, or "
        "{lo, hi, zero, bounce, stiffness, damping}.",
    )
    motor: Motor | None = None
    drive: Drive | None = Field(
        None, description="A command: position (PD), velocity (motor) or torque mode (docs/language.md#joint-commands)."
    )
    dynamics: Dynamics | None = Field(None, description="Damping, dry friction, armature, effort and rate limits.")

    _v = field_validator("axis", "axis2", "anchor", mode="before")(finite_vec)

    @model_validator(mode="after")
    def _check(self) -> Joint:  # noqa: C901 - one list of rules
        if sum(c * c for c in self.axis) < 1e-12:
            raise ValueError("expected a non-zero axis, found (0, 0, 0)")
        if isinstance(self.limits, tuple) and self.limits[0] > self.limits[1]:
            raise ValueError(f"expected limits [lo, hi] with lo <= hi, found {list(self.limits)}")
        if isinstance(self.limits, Limits) and self.limits.zero == "absolute" and self.type not in ("slider", "hinge"):
            raise ValueError(f"`zero: absolute` is defined for sliders and hinges, not a {self.type} joint")
        if self.type in ("ball", "fixed") and (self.limits is not None or self.motor is not None):
            raise ValueError(f"a {self.type} joint takes no limits or motor")
        if self.drive is not None and self.type not in ("slider", "hinge"):
            raise ValueError(f"`drive` commands sliders and hinges, not a {self.type} joint")
        if self.drive is not None and self.motor is not None:
            raise ValueError("a joint takes a motor or a drive, not both (`drive: {vel, fmax}` is the motor)")
        if self.type not in ("slider", "hinge") and self.dynamics is not None:
            raise ValueError(f"`dynamics` is defined for sliders and hinges, not a {self.type} joint")
        if self.type == "universal" and self.axis2 is None:
            raise ValueError("a universal joint needs axis2")
        if self.axis2 is not None:
            a, b = self.axis, self.axis2
            cross = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
            if math.hypot(*cross) <= 1e-6 * math.hypot(*a) * math.hypot(*b):
                raise ValueError(f"expected axis2 not parallel to axis, found {list(a)} and {list(b)}")
        if self.bodies[0] == "environment":
            raise ValueError("the first body of a joint must be a body, found `environment`")
        return self


class PairSurface(Surface):
    bodies: tuple[Name, Name] = Field(description="The two bodies (or body groups) this surface is for.")


__all__ = [
    "Body", "BodyArray", "Cylinder", "Drive", "Dynamics", "Joint", "Limits", "Motor", "NonNegFloat", "PairSurface",
    "Plane", "World",
]  # fmt: skip
