"""The Foxglove layout for the scenarios a command ran: which message paths their assertions read.

Each assertion's expression names quantities (``box.pos.z``, ``slider.position``, ``state.door_open``,
``max(crate.pos.z)``, ``contact(box, door)``); each becomes the message path Foxglove plots it by
(:mod:`runner.trace.layout`). An array's name stands for its first copies. A body's height is always
among the plots, so the Plot panel has a body's z even when no assertion reads one.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from backends.types import Motion, Shape, ShapeKind
from reports.trace_format import LAYOUT_FILE, TOPIC_BODIES, TOPIC_JOINTS, TOPIC_TF, parts_by_topic
from runner.compile.program import Program, build_program
from runner.errors import TraceError
from runner.exec.exits import classify, most_severe
from runner.language import model_assertions as A
from runner.language.expressions import compile_expression
from runner.language.load import LoadedScenario
from runner.trace import layout as lt
from runner.trace.output import write_error

__all__ = ["layout_spec", "leave_layout", "write_layouts"]

_EXPRESSION_FIELDS = ("value", "check", "always", "never", "eventually", "max_of", "min_of")
_GROUP_MEMBERS = 3  # an array's name plots its first copies


@dataclass(frozen=True)
class _Names:
    """What a scenario's names plot as, worked out once per scenario: the part of /bodies or /joints that
    holds each body and joint (/bodies/2 ... beyond 8,000), and the arrays' copies."""

    bodies: dict[str, str]
    joints: dict[str, str]
    groups: Mapping[str, list[str]]

    @classmethod
    def of(cls, program: Program) -> _Names:
        def topics(topic: str, names: Sequence[str]) -> dict[str, str]:
            return {name: t for t, (_, part) in parts_by_topic(topic, names).items() for name in part}

        return cls(topics(TOPIC_BODIES, [b.name for b in program.world.bodies]),
                   topics(TOPIC_JOINTS, [j.name for j in program.world.joints]), program.groups)  # fmt: skip


def _quantity(name: str, names: _Names) -> list[lt.PlotPath]:
    """The plot paths of one dotted name (nothing for time, parameters and unknown names)."""
    bodies, joints = names.bodies, names.joints
    head, _, rest = name.partition(".")
    if head == "state" and rest:
        return [lt.PlotPath(lt.state_path(rest), name)]
    if head in joints and rest in ("position", "velocity", "force"):
        return [lt.PlotPath(lt.joint_path(head, rest, joints[head]), name)]
    members = [head] if head in bodies else names.groups.get(head, [])[:_GROUP_MEMBERS]
    field, _, component = rest.partition(".")
    out = []
    for body in members:
        if field == "speed":
            out += [lt.PlotPath(lt.body_path(body, "vel", c, bodies[body]), f"{body}.vel.{c}") for c in "xyz"]
        elif field in ("pos", "vel", "angvel", "quat"):
            comps = [component] if component else ("wxyz" if field == "quat" else "xyz")
            out += [lt.PlotPath(lt.body_path(body, field, c, bodies[body]), f"{body}.{field}.{c}") for c in comps]
    return out


def _assertion_paths(assertion: object, names: _Names) -> list[lt.PlotPath]:
    if isinstance(assertion, A.ContactAssertion):
        a, b = assertion.contact
        return [lt.PlotPath(f'/contacts.pairs[:]{{a=="{x}"}}{{b=="{y}"}}.normal_force', f"contact {x}-{y} force")
                for x, y in ((a, b), (b, a))]  # fmt: skip
    out = []
    for field in _EXPRESSION_FIELDS:
        text = getattr(assertion, field, None)
        if isinstance(text, str):
            for name in sorted(compile_expression(text).names):
                out += _quantity(name, names)
    return out


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
        for assertion in case.model.assertions:
            plots += _assertion_paths(assertion, names)
        if not any(p.value.startswith(TOPIC_TF) and p.value.endswith(".translation.z") for p in plots):
            body = _first_dynamic(program)
            if body is not None:
                plots.append(lt.PlotPath(lt.body_path(body, "pos", "z"), f"{body}.pos.z"))
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
    """``foxglove-layout.json`` in each folder that received these cases' traces. A write that fails is an
    :class:`~runner.errors.OutputError` (a full disk, exit 74) or a :class:`~runner.errors.TraceError`
    (a folder that cannot be used, exit 2), and leaves no file behind."""
    spec = layout_spec(cases)
    for folder in dict.fromkeys(folders):
        try:
            lt.write_layout(folder, spec)
        except OSError as exc:
            raise write_error(exc, str(folder / LAYOUT_FILE)) from None


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
