"""Compile a validated scenario's physics into an engine-neutral :class:`CompiledWorld`.

Masses and inertias follow ODE's dMassSet* functions (see backends/types.py); shapes are scaled by the
body's uniform scale as Panda3D scales a node; poses become quaternions (w, x, y, z).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from backends.geometry import IDENTITY, quat_normalize
from backends.types import (
    NO_DYNAMICS,
    BodySpec,
    CompiledWorld,
    Fluid,
    JointKind,
    JointSpec,
    Motion,
    Motor,
    PairSurface,
    Shape,
    ShapeKind,
)
from runner.compile.joints import drive_motor, dynamics, initial_motor, stops, zero_offset
from runner.compile.robot_start import mimic_starts, start_values
from runner.compile.robots import compile_robots
from runner.compile.sensed import reaction_joints
from runner.compile.surfaces import compiled_surface
from runner.language import model_actions as Act
from runner.language.hpr import hpr_to_quat
from runner.language.model import Scenario
from runner.language.model_inertia import principal_inertia
from runner.language.model_physics import Body, Limits
from runner.language.model_walk import all_actions
from runner.language.names import BodyInstance, expand_bodies, groups
from runner.language.robot_desc import ModelDesc

#: Kinematic bodies get a mass only because some engines need one; it never affects their motion.
KINEMATIC_DENSITY = 1000.0
PALETTE = [
    (0.85, 0.55, 0.25, 1.0),
    (0.35, 0.55, 0.85, 1.0),
    (0.45, 0.75, 0.40, 1.0),
    (0.80, 0.35, 0.45, 1.0),
    (0.65, 0.50, 0.80, 1.0),
    (0.90, 0.80, 0.35, 1.0),
]
STATIC_COLOR = (0.55, 0.55, 0.55, 1.0)


def shape_of(body: Body) -> Shape:
    s = body.scale
    if body.box is not None:
        return Shape(ShapeKind.BOX, size=(body.box[0] * s, body.box[1] * s, body.box[2] * s))
    if body.sphere is not None:
        return Shape(ShapeKind.SPHERE, radius=body.sphere * s)
    if body.capsule is not None:
        return Shape(ShapeKind.CAPSULE, radius=body.capsule.radius * s, length=body.capsule.length * s)
    if body.cylinder is not None:
        return Shape(ShapeKind.CYLINDER, radius=body.cylinder.radius * s, length=body.cylinder.length * s)
    return Shape(ShapeKind.PLANE)


def volume(shape: Shape) -> float:
    r, length = shape.radius, shape.length
    if shape.kind is ShapeKind.BOX:
        return shape.size[0] * shape.size[1] * shape.size[2]
    if shape.kind is ShapeKind.SPHERE:
        return 4.0 / 3.0 * math.pi * r**3
    if shape.kind is ShapeKind.CAPSULE:
        return math.pi * r * r * length + 4.0 / 3.0 * math.pi * r**3
    if shape.kind is ShapeKind.CYLINDER:
        return math.pi * r * r * length
    return 0.0


def mass_properties(shape: Shape, mass: float) -> tuple[float, float, float]:
    """Principal inertia for ``mass`` spread over ``shape`` (ODE mass.cpp formulas)."""
    r, length = shape.radius, shape.length
    if shape.kind is ShapeKind.BOX:
        x, y, z = shape.size
        return (mass / 12 * (y * y + z * z), mass / 12 * (x * x + z * z), mass / 12 * (x * x + y * y))
    if shape.kind is ShapeKind.SPHERE:
        i = 0.4 * mass * r * r
        return (i, i, i)
    if shape.kind is ShapeKind.CYLINDER:
        side = mass * (0.25 * r * r + length * length / 12.0)
        return (side, side, 0.5 * mass * r * r)
    if shape.kind is ShapeKind.CAPSULE:
        # dMassSetCapsule with the mass split between the cylinder and the two half-spheres by volume
        m1 = math.pi * r * r * length
        m2 = 4.0 / 3.0 * math.pi * r**3
        k = mass / (m1 + m2)
        m1, m2 = m1 * k, m2 * k
        side = m1 * (0.25 * r * r + length * length / 12.0) + m2 * (0.4 * r * r + 0.375 * r * length + 0.25 * length**2)
        return (side, side, (0.5 * m1 + 0.4 * m2) * r * r)
    return (0.0, 0.0, 0.0)


def orientation(body: Body) -> tuple[float, float, float, float]:
    if body.quat is not None:
        return quat_normalize(body.quat)
    if body.hpr is not None:
        return hpr_to_quat(body.hpr)
    return IDENTITY


def _position(inst: BodyInstance) -> tuple[float, float, float]:
    body = inst.body
    if body.array is None:
        return body.pos
    ix, iy, iz = inst.index
    sp, shift = body.array.spacing, body.array.layer_shift
    return tuple(body.pos[k] + (ix, iy, iz)[k] * sp[k] + iz * shift[k] for k in range(3))  # type: ignore[return-value]


def compile_body(inst: BodyInstance, number: int) -> BodySpec:
    body = inst.body
    shape = shape_of(body)
    motion = Motion(body.motion)
    if motion is Motion.STATIC:
        mass = 0.0
    elif body.mass is not None:
        mass = body.mass
    else:
        mass = (body.density or KINEMATIC_DENSITY) * volume(shape)
    inertia = mass_properties(shape, mass) if mass > 0 else (0.0, 0.0, 0.0)
    axes = IDENTITY
    if body.inertia is not None:  # the body's own (runner.language.model_inertia)
        inertia, axes = principal_inertia(body.inertia)
    given = (
        tuple(body.color)
        if body.color is not None
        else (STATIC_COLOR if motion is Motion.STATIC else PALETTE[number % len(PALETTE)])
    )
    color = (float(given[0]), float(given[1]), float(given[2]), float(given[3]) if len(given) > 3 else 1.0)
    return BodySpec(
        name=inst.name,
        motion=motion,
        shape=shape,
        mass=mass,
        inertia=inertia,
        pos=_position(inst),
        quat=orientation(body),
        lin_vel=body.vel,
        ang_vel=body.angvel,
        color=color,
        inertia_quat=axes,
    )


def joint_zeros(
    model: Scenario, world: CompiledWorld, robots: Mapping[str, ModelDesc] | None = None
) -> dict[str, float]:
    """Per joint whose zero is not the start, what to add to the backend's reading (from the start) to read
    it from the stated zero (runner.compile.joints): a robot joint's start position (`initial`) too."""
    by_name = {b.name: b for b in world.bodies}
    zeros = {
        name: zero_offset(joint, _unit(joint.axis), by_name)
        for name, joint in model.joints.items()
        if isinstance(joint.limits, Limits) and joint.limits.zero == "absolute"
    }
    for rname, robot in model.robots.items():
        if robots is not None and rname in robots:
            desc = robots[rname]
            values = mimic_starts(desc, start_values(robot, desc, as_file=model.world.options == "model"))
            zeros.update({f"{rname}.{j}": q for j, (q, _) in values.items() if q != 0.0})
    return zeros


def motor_targets(model: Scenario) -> frozenset[str]:
    """The joints a `motor` action, or a `drive` action in velocity mode, drives."""
    actions = [a for a, _ in all_actions(model)]
    return frozenset(a.motor.joint for a in actions if isinstance(a, Act.MotorAction)) | frozenset(
        a.drive.joint for a in actions if isinstance(a, Act.DriveAction) and a.drive.mode == "velocity"
    )


def _unit(v: Sequence[float]) -> tuple[float, float, float]:
    n = math.sqrt(sum(c * c for c in v))
    return (v[0] / n, v[1] / n, v[2] / n)


def _fluid(model: Scenario, robots: Fluid | None) -> Fluid | None:
    """The scenario's `world.fluid`, which replaces the robots' (an MJCF `<option>`); None where it has neither
    density nor viscosity (MuJoCo computes no fluid force then, wind or not)."""
    given = model.world.fluid
    if given is None:
        return robots
    if given.density > 0 or given.viscosity > 0:
        return Fluid(given.density, given.viscosity, given.wind)
    return None


def compile_world(model: Scenario, name: str, robots: Mapping[str, ModelDesc] | None = None) -> CompiledWorld:
    """The world; ``robots`` holds the model of every entry of ``model.robots`` (runner.language.robots)."""
    instances = expand_bodies(model)
    bodies = tuple(compile_body(inst, i) for i, inst in enumerate(instances))
    parts = compile_robots(model, robots or {}, tuple(b.name for b in bodies), groups(model), motor_targets(model))
    positions = {b.name: b.pos for b in bodies}
    by_name = {b.name: b for b in bodies}
    joints = []
    for jname, joint in model.joints.items():
        other = None if joint.bodies[1] == "environment" else joint.bodies[1]
        lo, hi = stops(joint, zero_offset(joint, _unit(joint.axis), by_name))
        limits = joint.limits if isinstance(joint.limits, Limits) else None
        joints.append(
            JointSpec(
                name=jname,
                kind=JointKind(joint.type),
                body=joint.bodies[0],
                other=other,
                axis=_unit(joint.axis),
                axis2=_unit(joint.axis2) if joint.axis2 is not None else None,
                anchor=joint.anchor if joint.anchor is not None else positions[joint.bodies[0]],
                lo=lo,
                hi=hi,
                stop_bounce=limits.bounce if limits is not None else 0.0,
                stop_stiffness=limits.stiffness if limits is not None else None,
                stop_damping=limits.damping if limits is not None else None,
                motor=initial_motor(
                    Motor(joint.motor.vel, joint.motor.fmax) if joint.motor is not None else drive_motor(joint.drive),
                    dynamics(NO_DYNAMICS, joint.dynamics),
                    driven=False,
                ),
                dynamics=dynamics(NO_DYNAMICS, joint.dynamics),
            )
        )
    members = {**groups(model), **parts.groups}
    pairs: list[PairSurface] = []
    for override in model.surfaces:
        surface = compiled_surface(override)
        side_a = members.get(override.bodies[0], [override.bodies[0]])
        side_b = members.get(override.bodies[1], [override.bodies[1]])
        pairs.extend(PairSurface(a, b, surface) for a in side_a for b in side_b if a != b)
    pairs.extend(parts.surfaces)  # after the scenario's pairs, which win (CompiledWorld.surface: the first)
    return CompiledWorld(
        name=name,
        gravity=model.world.gravity,
        dt=model.world.dt,
        substeps=model.world.substeps,
        duration=model.world.duration,
        bodies=bodies + parts.bodies,
        joints=tuple(joints) + parts.joints,
        default_surface=compiled_surface(model.surface),
        pair_surfaces=tuple(pairs),
        backend_options={k: dict(v) for k, v in model.backend_options.items()},
        excluded_pairs=parts.excluded,
        models=parts.models,
        joint_chains=parts.chains,
        couplings=parts.couplings,
        fluid=_fluid(model, parts.fluid),
        model_options=model.world.options == "model",
        contact_points=model.trace.contact_points,
        reaction_joints=reaction_joints(model, [j.name for j in (*joints, *parts.joints)]),
    )
