"""Everything a run needs, compiled once from a loaded scenario: world, intervals, events, assertions."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import CompiledWorld, Motion
from runner.compile.interval_specs import FuncSpec, LerpSpec, ParallelSpec, SequenceSpec, SoundSpec, WaitSpec
from runner.compile.sensed import sensor_quantities
from runner.compile.solids import NodeDef, SolidDef
from runner.compile.world import compile_world, joint_zeros
from runner.errors import ScenarioValidationError
from runner.language import model_behaviour as B
from runner.language.expressions import Expression, compile_expression
from runner.language.load import LoadedScenario
from runner.language.names import expand_bodies, groups, robot_frames, robot_groups
from runner.language.refs import expressions_in
from runner.language.sounds import SoundInfo, read_info

STEP_EPS = 1e-9  # a timed input at t is due at the first step whose time is >= t - STEP_EPS


@dataclass(frozen=True)
class TimedInput:
    """An input event due at a step (its time as written, rounded to the step it falls on)."""

    step: int
    time: float  # as written (the scheduled time)
    event: str


@dataclass(frozen=True)
class HandlerSpec:
    """The actions run for an event, and how often (docs/language.md, "Handlers")."""

    actions: tuple[Any, ...]
    once: bool = False  # only for the event's first delivery
    min_interval: float | None = None  # not again within this many seconds of the last run


@dataclass(frozen=True)
class TriggerSpec:
    """An event raised when ``when`` becomes true (false or unknown at the previous check, true now)."""

    event: str
    when: str  # the expression's text (a key of Program.expressions)
    once: bool = False  # never re-armed; otherwise re-armed when the condition is false again


@dataclass
class Program:
    """A loaded scenario variant compiled for the step loop: its world, steps, inputs, intervals and handlers."""

    loaded: LoadedScenario
    world: CompiledWorld
    steps: int
    intervals: dict[str, tuple[str, Any]]  # id -> (Panda3D name, IntervalSpec)
    handlers: dict[str, HandlerSpec]
    triggers: list[TriggerSpec]
    inputs: list[TimedInput]
    nodes: list[NodeDef]
    colliders: list[str]
    contact_colliders: list[int]
    expressions: dict[str, Expression]
    sounds: dict[str, SoundInfo]
    groups: dict[str, list[str]]
    start_hpr: dict[str, tuple[float, float, float]]
    start_scale: dict[str, float]
    #: joint -> what to add to the backend's reading to read it from the joint's stated zero (nonzero only)
    joint_zeros: dict[str, float]
    #: `<robot>.<frame>` -> (its body, position and orientation in the body frame): runner.sim.frames
    frames: dict[str, tuple[str, tuple[float, float, float], tuple[float, float, float, float]]] = field(
        default_factory=dict
    )
    #: the sensor quantities the expressions read, one body, joint or frame each (runner.compile.sensed)
    sensors: list[str] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.loaded.model.scenario


def _interval_spec(step: B.Step, model: Any, sounds: dict[str, SoundInfo], seen: tuple[str, ...] = ()) -> Any:
    if step.lerp is not None:
        lerp = step.lerp
        return LerpSpec(
            body=lerp.body,
            duration=lerp.duration,
            blend=lerp.blend,
            pos=lerp.pos,
            hpr=lerp.hpr,
            scale=lerp.scale,
            start_pos=lerp.start_pos,
            start_hpr=lerp.start_hpr,
            start_scale=lerp.start_scale,
        )
    if step.wait is not None:
        return WaitSpec(duration=step.wait)
    if step.func is not None:
        return FuncSpec(actions=tuple(step.func), label="func")
    if step.sound is not None:
        spec = step.sound if isinstance(step.sound, B.SoundStep) else B.SoundStep(sound=step.sound)
        length = sounds[spec.sound].length
        duration = spec.duration if spec.duration is not None else max(length - spec.start_time, 0.0)
        return SoundSpec(
            sound=spec.sound,
            duration=duration,
            volume=spec.volume,
            loop=spec.loop,
            start_time=spec.start_time,
            length=length,
        )
    if step.interval is not None:
        if step.interval in seen:
            raise ValueError(f"interval `{step.interval}` contains itself")
        return _interval_spec(model.intervals[step.interval], model, sounds, (*seen, step.interval))
    children = tuple(_interval_spec(c, model, sounds, seen) for c in (step.sequence or step.parallel or []))
    if step.sequence is not None:
        return SequenceSpec(children=children, duration=step.duration)
    return ParallelSpec(children=children, duration=step.duration)


def _solid(solid: B.Solid) -> SolidDef:
    if solid.sphere is not None:
        return SolidDef("sphere", np.asarray(solid.sphere.center, float), radius=solid.sphere.radius)
    if solid.polygon is not None:
        verts = np.asarray(solid.polygon, float)
        return SolidDef("polygon", verts.mean(axis=0), vertices=verts)
    box = solid.box
    if box is None:
        raise ValueError("a solid needs one of sphere, polygon or box")  # the model validation refuses it first
    return SolidDef("box", np.asarray(box.center, float), half=np.asarray(box.size, float) / 2.0)


def _expressions(model: Any) -> dict[str, Expression]:
    return {text: compile_expression(text) for text, _ in expressions_in(model)}


#: Dynamic bodies' masses (kg) and principal moments (kg m^2) must lie in these ranges: MuJoCo refuses
#: values below 1e-15 (mjMINVAL), and ODE in single precision aborts the process on zero or infinite ones.
MASS_RANGE = (1e-15, 1e30)


def check_world(world: CompiledWorld, loaded: LoadedScenario) -> None:
    """Refuse a world whose numbers were each in range but whose masses or inertias are not."""
    keys = {inst.name: inst.key for inst in expand_bodies(loaded.model)}
    keys.update({f"{r}.{link.name}": r for r, desc in loaded.robots.items() for link in desc.links})
    lo, hi = MASS_RANGE
    issues = []
    seen: set[str] = set()
    for b in world.bodies:
        if keys[b.name] in seen:
            continue  # the copies of an array are alike: one issue for them all
        if b.motion is Motion.DYNAMIC and not all(lo <= v <= hi for v in (b.mass, *b.inertia)):
            seen.add(keys[b.name])
            moments = ", ".join(f"{v:.3g}" for v in b.inertia)
            issues.append(
                loaded.positions.issue(
                    ("robots" if "." in b.name else "bodies", keys[b.name]),
                    f"body `{b.name}` has mass {b.mass:.3g} kg and principal moments {moments} kg m^2; "
                    f"expected each within [{lo:g}, {hi:g}] (change its size, mass or density)",
                )
            )
    if issues:
        raise ScenarioValidationError(issues)


def build_program(loaded: LoadedScenario) -> Program:
    from runner.language.hpr import quat_to_hpr

    model = loaded.model
    world = compile_world(model, model.scenario, loaded.robots)
    check_world(world, loaded)
    base = Path(loaded.path).parent
    sounds = {name: read_info((base / rel).resolve()) for name, rel in model.sounds.items()}
    intervals = {
        ival: (d.name or ival, _interval_spec(d, model, sounds, (ival,))) for ival, d in model.intervals.items()
    }
    steps = max(1, int(math.floor(world.duration / world.dt + 0.5)))
    inputs: list[TimedInput] = []
    for item in model.inputs:
        times = (
            [item.at] if item.repeat is None else [item.at + k * item.repeat.every for k in range(item.repeat.count)]
        )
        for t in times:
            step = max(0, math.ceil(t / world.dt - STEP_EPS))
            if step < steps:
                inputs.append(TimedInput(step, t, item.event))
    inputs.sort(key=lambda x: (x.step, x.time))
    index = {b.name: i for i, b in enumerate(world.bodies)}
    nodes = [
        NodeDef(name, index[n.body], tuple(_solid(s) for s in n.all_solids()))
        for name, n in model.collisions.nodes.items()
    ]
    start_hpr: dict[str, tuple[float, float, float]] = {}
    start_scale: dict[str, float] = {}
    instances = expand_bodies(model)
    for inst, spec in zip(instances, world.bodies[: len(instances)], strict=True):
        body = inst.body
        start_hpr[inst.name] = body.hpr if body.hpr is not None else quat_to_hpr(spec.quat)
        start_scale[inst.name] = body.scale
    for spec in world.bodies[len(instances) :]:  # the robots' links
        start_hpr[spec.name] = quat_to_hpr(spec.quat)
        start_scale[spec.name] = 1.0
    return Program(
        loaded=loaded,
        world=world,
        steps=steps,
        intervals=intervals,
        handlers={event: HandlerSpec(*_handler(h)) for event, h in model.on.items()},
        triggers=[TriggerSpec(name, t.when, t.once) for name, t in model.triggers.items()],
        inputs=inputs,
        nodes=nodes,
        colliders=list(model.collisions.from_),
        contact_colliders=[index[b] for b in model.collisions.contacts_from],
        expressions=_expressions(model),
        sounds=sounds,
        groups={**groups(model), **robot_groups(loaded.robots)},
        start_hpr=start_hpr,
        start_scale=start_scale,
        joint_zeros=joint_zeros(model, world, loaded.robots),
        frames=robot_frames(loaded.robots),
        sensors=sensor_quantities(model, world, {**groups(model), **robot_groups(loaded.robots)},
                                  set(robot_frames(loaded.robots))),
    )


def _handler(handler: Any) -> tuple[tuple[Any, ...], bool, float | None]:
    actions, once, min_interval = B.handler_parts(handler)
    return tuple(actions), once, min_interval
