"""Place a scenario's robots in the world: links become bodies `<robot>.<link>`, joints `<robot>.<joint>`.

A link's body frame is its URDF link frame (MJCF: body frame) at the model's zero configuration, moved by
the robot's ``pos``/``hpr``; its inertial frame is the model's tensor diagonalised (principal moments and
the rotation to their axes); its shapes keep their local poses. A model's root is static when ``fixed``
(an MJCF model's world body always is); joints to a static link are joints to the environment. A joint's
two links never touch (URDF's convention; MuJoCo's parent-child rule), nor the pairs the scenario excludes,
nor any two links of a model without ``self_collision`` (a URDF's default, as pybullet's ``loadURDF``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

from backends.geometry import IDENTITY, quat_mul, quat_rotate
from backends.types import (
    BodySpec,
    Capability,
    Fluid,
    JointCoupling,
    JointDynamics,
    JointKind,
    JointSpec,
    ModelFile,
    Motion,
    Motor,
    PairSurface,
    Shape,
    ShapeKind,
    Surface,
)
from runner.compile.joints import drive_motor, dynamics, initial_motor
from runner.compile.robot_start import (
    LinkMotion,
    joint_motions,
    link_motions,
    mimic_starts,
    root_motion,
    start_values,
)
from runner.compile.surfaces import compiled_surface
from runner.language.hpr import hpr_to_quat
from runner.language.model import Scenario
from runner.language.model_actions import ControlAction
from runner.language.model_physics import Limits
from runner.language.model_robots import Robot
from runner.language.model_walk import all_actions
from runner.language.robot_desc import JointDesc, LinkDesc, ModelDesc, principal_axes, vec

PALETTE = [(0.80, 0.45, 0.20, 1.0), (0.30, 0.50, 0.80, 1.0), (0.40, 0.70, 0.35, 1.0), (0.75, 0.30, 0.40, 1.0)]
STATIC_COLOR = (0.55, 0.55, 0.55, 1.0)


@dataclass(frozen=True)
class RobotParts:
    """A robot's links and joints as world bodies and joints, with the pairs it excludes and its surfaces."""

    bodies: tuple[BodySpec, ...]
    joints: tuple[JointSpec, ...]
    excluded: tuple[tuple[str, str], ...]
    surfaces: tuple[PairSurface, ...]  # link overrides: (link, other body) for every other body
    groups: dict[str, list[str]]  # robot -> its links' body names
    models: tuple[ModelFile, ...] = ()  # the MJCF robots, for an engine that builds them from the file
    chains: tuple[tuple[str, ...], ...] = ()  # joints moving one body together, in order (MJCF)
    couplings: tuple[JointCoupling, ...] = ()  # URDF <mimic> joints
    fluid: Fluid | None = None  # the first MJCF robot's medium (CompiledWorld.fluid)


def _placement(robot: Robot) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    return robot.pos, hpr_to_quat(robot.hpr) if robot.hpr is not None else IDENTITY


def _add(a: tuple[float, float, float], b: tuple[float, float, float]) -> tuple[float, float, float]:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def is_static(robot: Robot, desc: ModelDesc, link: str) -> bool:
    return link == desc.root and (robot.fixed or robot.format == "mjcf")


def link_body(
    robot_name: str, robot: Robot, desc: ModelDesc, link: LinkDesc, number: int, motion: LinkMotion | None = None
) -> BodySpec:
    """A link as a body, placed and moving as ``motion`` says (default: at its zero pose, at rest)."""
    import numpy as np

    pos0, quat0 = _placement(robot)
    static = is_static(robot, desc, link.name)
    override = robot.links.get(link.name)
    given = override.color if override is not None and override.color is not None else link.color
    if given is None:
        given = STATIC_COLOR if static else PALETTE[number % len(PALETTE)]
    color = (float(given[0]), float(given[1]), float(given[2]), float(given[3]) if len(given) > 3 else 1.0)
    visuals = link.visuals
    if override is not None and override.color is not None:  # the scenario's colour paints the whole link
        visuals = tuple(replace(v, color=None) for v in visuals)
    if static:
        mass, inertia, com, axes = 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), IDENTITY
    else:
        mass, com = link.mass, link.com
        inertia, axes = principal_axes(np.asarray(link.inertia, dtype=float))
    pos, quat = link.pos, link.quat
    lin_vel = ang_vel = (0.0, 0.0, 0.0)
    if motion is not None and not static:
        at = motion.apply(np.asarray(link.pos, dtype=float))
        pos, quat = vec(at), quat_mul(motion.quat, link.quat)
        lin_vel, ang_vel = quat_rotate(quat0, vec(motion.velocity(at))), quat_rotate(quat0, vec(motion.omega))
    return BodySpec(
        name=f"{robot_name}.{link.name}",
        motion=Motion.STATIC if static else Motion.DYNAMIC,
        shape=Shape(ShapeKind.COMPOUND),
        mass=mass,
        inertia=inertia,
        pos=_add(pos0, quat_rotate(quat0, pos)),
        quat=quat_mul(quat0, quat),
        lin_vel=lin_vel,
        ang_vel=ang_vel,
        color=color,
        shapes=link.shapes,
        com=com,
        inertia_quat=axes,
        visuals=visuals,
    )


def actuator_effort(desc: ModelDesc, joint: JointDesc) -> JointDynamics:
    """The joint's dynamics with, where the model gives it no effort limit, its actuators' largest force
    limit as one: |gear| x max(|lo|, |hi|) of a `forcerange` (docs/robots.md, "MJCF actuators")."""
    limits = [abs(a.gear) * max(abs(a.forcerange[0]), abs(a.forcerange[1]))
              for a in desc.actuators if a.joint == joint.name and a.forcerange is not None]  # fmt: skip
    if not limits or joint.dynamics.effort is not None:
        return joint.dynamics
    return replace(joint.dynamics, effort=max(limits))


def commanded_actuators(model: Scenario, name: str) -> frozenset[str]:
    """The actuators of robot ``name`` the scenario drives: given a `ctrl`, or named by a `control` action."""
    robot = model.robots[name]
    named = {a.control.actuator for a, _ in all_actions(model) if isinstance(a, ControlAction)}
    return frozenset(robot.actuators) | frozenset(n[len(name) + 1 :] for n in named if n.startswith(f"{name}."))


def _joint(
    robot_name: str,
    robot: Robot,
    desc: ModelDesc,
    joint: JointDesc,
    motions: Mapping[str, tuple[LinkMotion, LinkMotion]],
    start: float,
    driven: bool,
) -> JointSpec:
    """The joint at the start pose (its axis turned with the parent, its anchor with the child), its stops
    from there (``start``: the position from the model's zero); ``driven``: a motor action drives it."""
    import numpy as np

    pos0, quat0 = _placement(robot)
    override = robot.joints.get(joint.name)
    lo, hi = joint.lo, joint.hi
    motor = None
    dyn = dynamics(actuator_effort(desc, joint), override.dynamics if override is not None else None)
    if dyn.stiffness > 0:  # the model's spring rest counts from its zero; a JointSpec's from the start
        dyn = replace(dyn, springref=dyn.springref - start)
    if override is not None:
        if override.free:
            lo = hi = None
        elif isinstance(override.limits, Limits):
            lo, hi = override.limits.lo, override.limits.hi
        elif override.limits is not None:
            lo, hi = override.limits
        if override.motor is not None:
            motor = Motor(override.motor.vel, override.motor.fmax)
        motor = drive_motor(override.drive) or motor
    servo = override is not None and override.servo is not None  # the servo sets it every step (runner.sim.servo)
    motor = initial_motor(motor, dyn, servo or driven)  # a motor action: off until the action sets it
    limits = override.limits if override is not None and isinstance(override.limits, Limits) else None
    other = None if is_static(robot, desc, joint.parent) else f"{robot_name}.{joint.parent}"
    axis, anchor = joint.axis, joint.anchor
    carried = motions.get(joint.name)  # (the frame carrying the joint, the frame it moves): runner.compile.robot_start
    if carried is not None:
        axis = vec(carried[0].rot @ np.asarray(joint.axis, dtype=float))
        anchor = vec(carried[1].apply(np.asarray(joint.anchor, dtype=float)))
    return JointSpec(
        name=f"{robot_name}.{joint.name}",
        kind=JointKind(joint.kind),
        body=f"{robot_name}.{joint.child}",
        other=other,
        axis=quat_rotate(quat0, axis),
        anchor=_add(pos0, quat_rotate(quat0, anchor)),
        lo=None if lo is None else lo - start,
        hi=None if hi is None else hi - start,
        stop_bounce=limits.bounce if limits is not None else 0.0,
        stop_stiffness=limits.stiffness if limits is not None else None,
        stop_damping=limits.damping if limits is not None else None,
        motor=motor,
        dynamics=dyn,
    )


def compile_robots(
    model: Scenario,
    robots: Mapping[str, ModelDesc],
    others: tuple[str, ...],
    arrays: Mapping[str, list[str]],
    driven: frozenset[str] = frozenset(),
) -> RobotParts:
    """The robots' bodies, joints, excluded pairs and link surfaces, at their start (`initial`); ``others``
    are the hand-written bodies, ``arrays`` their groups, ``driven`` the joints motor actions drive."""
    bodies: list[BodySpec] = []
    joints: list[JointSpec] = []
    excluded: list[tuple[str, str]] = []
    link_surfaces: list[tuple[str, Surface]] = []
    group: dict[str, list[str]] = {}
    models: list[ModelFile] = []
    chains: list[tuple[str, ...]] = []
    couplings: list[JointCoupling] = []
    for name, robot in model.robots.items():
        desc = robots[name]
        values = mimic_starts(desc, start_values(robot, desc, as_file=model.world.options == "model"))
        root = root_motion(robot, desc)
        moved = values or root is not None
        motions = link_motions(desc, values, root) if moved else {}
        carriers = joint_motions(desc, values, root) if moved else {}
        for link in desc.links:
            bodies.append(link_body(name, robot, desc, link, len(bodies), motions.get(link.name)))
            override = robot.links.get(link.name)
            if override is not None and override.surface is not None:
                link_surfaces.append((f"{name}.{link.name}", compiled_surface(override.surface)))
        group[name] = [f"{name}.{link.name}" for link in desc.links]
        for joint in desc.joints:
            if joint.kind == "free":  # no joint: the body touches its parent (MuJoCo: the world) as any other
                continue
            if not (robot.format == "mjcf" and joint.parent == desc.root):  # MuJoCo: the world is no parent
                excluded.append((f"{name}.{joint.parent}", f"{name}.{joint.child}"))
            start = values.get(joint.name, (0.0, 0.0))[0]
            joints.append(_joint(name, robot, desc, joint, carriers, start, f"{name}.{joint.name}" in driven))
        excluded.extend((f"{name}.{a}", f"{name}.{b}") for a, b in robot.exclude)
        if not robot.collides_with_itself:  # pybullet's default for URDF: no two links of the model touch
            links = group[name]
            excluded.extend((a, b) for i, a in enumerate(links) for b in links[i + 1 :])
        excluded.extend((f"{name}.{a}", f"{name}.{b}") for a, b in desc.excluded)
        if robot.format == "mjcf":
            models.append(model_file(name, robot, desc, values, commanded_actuators(model, name)))
        chains.extend(joint_chains(name, desc))
        couplings.extend(joint_couplings(name, desc, values))
    members = {**arrays, **group}
    for a, b in model.exclude_contacts:
        for x in members.get(a, [a]):
            excluded.extend((x, y) for y in members.get(b, [b]) if x != y)
    everyone = list(others) + [b.name for b in bodies]
    surfaces = tuple(PairSurface(link, other, s) for link, s in link_surfaces for other in everyone if other != link)
    unique = tuple(dict.fromkeys((a, b) if a <= b else (b, a) for a, b in excluded))
    fluid = next((robots[name].fluid for name in model.robots if robots[name].fluid is not None), None)
    return RobotParts(
        tuple(bodies), tuple(joints), unique, surfaces, group, tuple(models), tuple(chains), tuple(couplings), fluid
    )


def joint_couplings(name: str, desc: ModelDesc, values: Mapping[str, tuple[float, float]]) -> list[JointCoupling]:
    """The model's `<mimic>` joints in the world's coordinates (each joint counted from its start ``values``):
    q + s = m (q_leader + s_leader) + offset gives the world offset m s_leader + offset - s."""
    out = []
    for joint in desc.joints:
        if joint.mimic is None:
            continue
        m, leader = joint.mimic.multiplier, joint.mimic.leader
        start, lead = values.get(joint.name, (0.0, 0.0))[0], values.get(leader, (0.0, 0.0))[0]
        offset = m * lead + joint.mimic.offset - start
        out.append(JointCoupling(f"{name}.{joint.name}", f"{name}.{leader}", m, offset))
    return out


def joint_chains(name: str, desc: ModelDesc) -> list[tuple[str, ...]]:
    """The joints of each link moved by several (MJCF), in the file's order: `CompiledWorld.joint_chains`."""
    moving: dict[str, list[str]] = {}
    for joint in desc.joints:
        if joint.kind not in ("fixed", "free"):
            moving.setdefault(joint.child, []).append(f"{name}.{joint.name}")
    return [tuple(names) for names in moving.values() if len(names) > 1]


def model_file(
    name: str, robot: Robot, desc: ModelDesc, values: Mapping[str, tuple[float, float]] | None = None,
    commanded: frozenset[str] = frozenset(),
) -> ModelFile:
    """An MJCF robot as its file: the description's links and joints are in MuJoCo's compiled order, welds
    (a body without a joint, `<body>_weld`, the description's only fixed joints) aside; ``values``: the
    joints' start (position from the model's zero, rate); ``commanded``: the actuators the scenario drives
    (one the runner's force law cannot reproduce needs the engine's own, ``actuator:native``)."""
    native = any(a.unmapped is not None for a in desc.actuators if a.name in commanded)
    pos, quat = _placement(robot)
    joints = tuple(f"{name}.{j.name}" for j in desc.joints if j.kind != "fixed")  # MJCF has no fixed joints
    return ModelFile(
        robot=name,
        path=desc.file,
        format=robot.format,
        pos=pos,
        quat=quat,
        bodies=tuple(f"{name}.{link.name}" for link in desc.links),
        joints=joints,
        needs=frozenset(Capability(n.capability) for n in desc.needs) | (
            frozenset({Capability.ACTUATOR_NATIVE}) if native else frozenset()
        ),
        start=tuple((f"{name}.{j}", q, v) for j, (q, v) in (values or {}).items()),
        xml=desc.upgraded[0] if desc.upgraded is not None else "",
        includes=desc.upgraded[1] if desc.upgraded is not None else (),
        need_sites=tuple((Capability(n.capability), f"{Path(desc.file).name}:{n.line}: {n.what}" if n.line else
                          f"{Path(desc.file).name}: {n.what}") for n in desc.needs),
    )  # fmt: skip
