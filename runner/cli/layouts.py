"""The Foxglove layout for the scenarios a command ran: which message paths their assertions read.

The quantities the assertions read (:func:`runner.compile.asserted.asserted_quantities`: ``box.pos.z``,
``crate_4.pos.z`` for every copy of an array, a robot's ``arm.link_7.pos.x`` and ``arm.joint_2.position``,
``state.door_open``, ``contact(box, door)``) each become the message paths Foxglove plots them by
(:mod:`runner.trace.layout`), with their unit, so that the layout groups them into one plot per unit. A body's
speed is plotted as its velocity's three components (Foxglove plots fields, not norms). A body's height is
always among the plots, so the metres plot has a body's z even when no assertion reads one.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from backends.types import JointKind, Motion, Shape, ShapeKind
from reports.trace_format import (
    LAYOUT_FILE,
    TOPIC_BODIES,
    TOPIC_JOINTS,
    TOPIC_SENSORS,
    TOPIC_TF,
    parts_by_topic,
    scenario_layout_file,
    sensor_field,
    sensor_unit,
)
from runner.compile.asserted import asserted_quantities
from runner.compile.program import Program, build_program
from runner.errors import TraceError
from runner.exec.exits import classify, most_severe
from runner.language.load import LoadedScenario
from runner.language.names import written
from runner.trace import layout as lt
from runner.trace.output import write_error

__all__ = ["layout_spec", "leave_layout", "write_layouts"]

_BODY_UNITS = {"pos": "m", "vel": "m/s", "angvel": "rad/s", "quat": "1"}


@dataclass(frozen=True)
class _Names:
    """What a scenario's names plot as, worked out once per scenario: the part of /bodies or /joints that
    holds each body and joint (/bodies/2 ... beyond 8,000), and each joint's kind."""

    bodies: dict[str, str]
    joints: dict[str, str]
    kinds: dict[str, JointKind]
    sensors: frozenset[str] = frozenset()  # the quantities on /sensors

    @classmethod
    def of(cls, program: Program) -> _Names:
        def topics(topic: str, names: Sequence[str]) -> dict[str, str]:
            return {name: t for t, (_, part) in parts_by_topic(topic, names).items() for name in part}

        return cls(topics(TOPIC_BODIES, [b.name for b in program.world.bodies]),
                   topics(TOPIC_JOINTS, [j.name for j in program.world.joints]),
                   {j.name: j.kind for j in program.world.joints}, frozenset(program.sensors))  # fmt: skip


def _joint_unit(kind: JointKind | None, field: str) -> str:
    linear = kind is JointKind.SLIDER
    if field == "position":
        return "m" if linear else "rad"
    if field == "velocity":
        return "m/s" if linear else "rad/s"
    return "N" if linear else "N·m"


def _paths(quantity: str, names: _Names) -> list[lt.PlotPath]:
    """The plot paths of one asserted quantity (none for a body's energy: no field holds it), labelled as an
    expression writes the quantity (`dog["8"].position`)."""
    if quantity.startswith("contact(") and quantity.endswith(")"):
        a, _, b = quantity[len("contact(") : -1].partition(", ")
        return [lt.PlotPath(f'/contacts.pairs[:]{{a=="{x}"}}{{b=="{y}"}}.normal_force', f"contact {x}-{y} force", "N")
                for x, y in ((a, b), (b, a))]  # fmt: skip
    if quantity in names.sensors:
        return [lt.PlotPath(f"{TOPIC_SENSORS}.{sensor_field(quantity)}", written(quantity), sensor_unit(quantity))]
    head, _, field = quantity.rpartition(".")
    if head == "state":
        return [lt.PlotPath(lt.state_path(field), quantity, "1")]
    if head in names.joints:
        unit = _joint_unit(names.kinds.get(head), field)
        return [lt.PlotPath(lt.joint_path(head, field, names.joints[head]), written(quantity), unit)]
    if field == "speed" and head in names.bodies:
        return [lt.PlotPath(lt.body_path(head, "vel", c, names.bodies[head]), written(f"{head}.vel.{c}"), "m/s")
                for c in "xyz"]  # fmt: skip
    body, _, part = head.rpartition(".")
    if body in names.bodies and part in _BODY_UNITS:
        return [lt.PlotPath(lt.body_path(body, part, field, names.bodies[body]), written(quantity), _BODY_UNITS[part])]
    return []


def _first_dynamic(program: Program) -> str | None:
    for b in program.world.bodies:
        if b.motion is Motion.DYNAMIC:
            return b.name
    return program.world.bodies[0].name if program.world.bodies else None


def layout_spec(cases: Sequence[LoadedScenario]) -> lt.LayoutSpec:
    """What the layout of a folder holding these cases' traces shows (each scenario once)."""
    plots: list[lt.PlotPath] = []
    transitions: list[str] = []
    spheres: list[tuple[tuple[float, ...], float]] = []
    seen: set[str] = set()
    for case in cases:
        key = f"{case.path}:{case.variant}"
        if key in seen:
            continue
        seen.add(key)
        program = build_program(case)
        names = _Names.of(program)
        for quantity in asserted_quantities(program):
            plots += _paths(quantity, names)
        if not any(p.value.startswith(TOPIC_TF) and p.value.endswith(".translation.z") for p in plots):
            body = _first_dynamic(program)
            if body is not None:
                plots.append(lt.PlotPath(lt.body_path(body, "pos", "z"), f"{body}.pos.z", "m"))
        transitions += [lt.state_path(name) for name, value in case.model.state.items() if not _number(value)]
        spheres += [(tuple(b.pos), _radius(b.shape)) for b in program.world.bodies
                    if b.shape.kind is not ShapeKind.PLANE]  # fmt: skip
    return lt.LayoutSpec(plots, list(dict.fromkeys(transitions)), spheres)


def _radius(shape: Shape) -> float:
    """The radius of the sphere around a shape, about its origin."""
    if shape.kind is ShapeKind.BOX:
        return math.hypot(*shape.size) / 2
    if shape.kind is ShapeKind.CAPSULE:
        return shape.length / 2 + shape.radius
    return math.hypot(shape.radius, shape.length / 2)  # sphere (length 0), cylinder


def _number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def write_layouts(folders: Iterable[Path], cases: Sequence[LoadedScenario]) -> None:
    """In each folder that received these cases' traces: ``foxglove-layout.json`` for all of them, and
    ``<scenario>.foxglove-layout.json`` for each scenario (its variants together), which a later command
    writing other scenarios into the folder leaves alone. A write that fails is an
    :class:`~runner.errors.OutputError` (a full disk, exit 74) or a :class:`~runner.errors.TraceError`
    (a folder that cannot be used, exit 2), and leaves no file behind."""
    by_scenario: dict[str, list[LoadedScenario]] = {}
    for case in cases:
        by_scenario.setdefault(case.model.scenario, []).append(case)
    own = {name: layout_spec(scenario_cases) for name, scenario_cases in by_scenario.items()}  # each built once
    every = lt.LayoutSpec([p for s in own.values() for p in s.plots],
                          list(dict.fromkeys(t for s in own.values() for t in s.transitions)),
                          [b for s in own.values() for b in s.spheres])  # fmt: skip
    specs = [(LAYOUT_FILE, every), *((scenario_layout_file(name), spec) for name, spec in own.items())]
    for folder in dict.fromkeys(folders):
        for name, spec in specs:
            try:
                lt.write_layout(folder, spec, name)
            except OSError as exc:
                raise write_error(exc, str(folder / name)) from None


def leave_layout(err: Console, folders: Iterable[Path], cases: Sequence[LoadedScenario], code: int) -> int:
    """After the runs: the layout beside their traces. A layout that cannot be written is said on stderr
    and makes the command's code the more severe of the two; the traces are kept either way."""
    try:
        write_layouts(folders, cases)
    except TraceError as exc:
        exit = classify(exc)
        err.print(f"[bold red]{escape(exit.label)}:[/] {escape(exit.message)}", markup=True)
        return most_severe([code, exit.code])
    return code
