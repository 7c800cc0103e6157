"""Cross-reference checks: every name used is defined, files exist, geometry makes sense."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from pathlib import Path as FsPath
from typing import Any

import numpy as np

from runner.errors import Issue, ScenarioValidationError
from runner.language import model_actions as Act
from runner.language import model_assertions as A
from runner.language.expressions import ExpressionError, compile_expression
from runner.language.model import Scenario
from runner.language.model_physics import Drive
from runner.language.model_walk import all_actions, walk_steps
from runner.language.names import (
    RESERVED,
    array_counts,
    check_name,
    expand_bodies,
    groups,
    readable_names,
    robot_links,
)
from runner.language.patterns import possible_events
from runner.language.robot_desc import ModelDesc
from runner.language.robot_refs import check_initial, check_motor, jointed_links
from runner.language.semantics import (
    check_backend_options,
    check_handlers,
    check_interval_cycles,
    check_times,
    unknown,
)
from runner.language.sounds import SoundFileError, read_info
from runner.language.yaml_source import Path, Positions

MAX_BODIES = 10_000
MAX_STEPS = 10_000_000
MAX_INPUTS = 100_000
MAX_SURFACE_PAIRS = 100_000


def _size_issues(model: Scenario, positions: Positions) -> list[Issue]:
    """Limits on what a small file can expand to, from the counts alone: a few hundred bytes of arrays,
    repeats or group surfaces would otherwise build millions of objects before any check."""
    size = {key: math.prod(array_counts(body)) for key, body in model.bodies.items()}
    bodies = sum(size.values())
    inputs = sum(1 if i.repeat is None else i.repeat.count for i in model.inputs)
    pairs = sum(size.get(s.bodies[0], 1) * size.get(s.bodies[1], 1) for s in model.surfaces)
    limits = [
        (bodies, MAX_BODIES, ("bodies",), "bodies (arrays expanded)"),
        (inputs, MAX_INPUTS, ("inputs",), "timed inputs (repeats expanded)"),
        (pairs, MAX_SURFACE_PAIRS, ("surfaces",), "body pairs in `surfaces` (groups expanded)"),
    ]
    return [
        positions.issue(where, f"expected at most {limit} {what}, found {found}")
        for found, limit, where, what in limits
        if found > limit
    ]


_unknown = unknown


def polygon_problem(vertices: list[tuple[float, float, float]]) -> str | None:
    pts = np.asarray(vertices, dtype=float)
    if len(pts) < 3:
        return f"a polygon needs at least 3 vertices, found {len(pts)}"
    normal = np.zeros(3)
    for i in range(len(pts)):
        normal += np.cross(pts[i], pts[(i + 1) % len(pts)])
    size = float(np.linalg.norm(normal))
    if size < 1e-12:
        return "the polygon's vertices are collinear or repeated (no area)"
    normal /= size
    extent = float(np.max(np.linalg.norm(pts - pts[0], axis=1)))
    if np.max(np.abs((pts - pts[0]) @ normal)) > 1e-6 * max(extent, 1.0):
        return "the polygon is not planar"
    for i in range(len(pts)):
        a, b, c = pts[i], pts[(i + 1) % len(pts)], pts[(i + 2) % len(pts)]
        if float(np.dot(np.cross(b - a, c - b), normal)) < -1e-12:
            return "the polygon is not convex"
    return None


def check_references(  # noqa: C901
    model: Scenario, positions: Positions, base_dir: FsPath, robots: Mapping[str, ModelDesc] | None = None
) -> None:
    robots = robots or {}
    issues: list[Issue] = []

    def bad(path: Path, message: str, at_key: bool = False) -> None:
        issues.append(positions.issue(path, message, at_key))

    steps = model.world.duration / model.world.dt
    if steps > MAX_STEPS:
        bad(("world", "duration"), f"expected at most {MAX_STEPS} steps (duration / dt), found {steps:.0f}")
    issues += _size_issues(model, positions)
    if issues:  # before anything expands arrays, repeats or pairs
        raise ScenarioValidationError(issues)
    instances = expand_bodies(model)
    body_names = {b.name for b in instances} | set(robot_links(robots))
    group_names = set(groups(model)) | set(robots)
    for name in [*model.bodies, *model.joints, *model.robots]:
        if name in RESERVED:
            kind = "bodies" if name in model.bodies else "joints" if name in model.joints else "robots"
            where = (kind, name)
            bad(where, f"`{name}` is a reserved name; choose another", at_key=True)
    for name in model.robots:
        if name in model.bodies or name in model.joints or name in groups(model):
            bad(("robots", name), f"robot `{name}` has the name of a body or joint; names must be unique", at_key=True)
    for i, excluded in enumerate(model.exclude_contacts):
        for j, ref in enumerate(excluded):
            if ref not in body_names and ref not in group_names:
                bad(("exclude_contacts", i, j), _unknown("body", ref, body_names | group_names))
    for joint_name in model.joints:
        if joint_name in body_names or joint_name in group_names:
            clash = f"joint `{joint_name}` has the name of a body; names must be unique"
            bad(("joints", joint_name), clash, at_key=True)
    for key, body in model.bodies.items():
        if body.array is not None and any(f"{key}_" in n and n in model.bodies for n in body_names):
            clash = next(n for n in model.bodies if n.startswith(f"{key}_") and n in body_names and n != key)
            bad(("bodies", clash), f"`{clash}` clashes with a copy of array `{key}`", at_key=True)
    for name, joint in model.joints.items():
        for i, ref in enumerate(joint.bodies):
            if ref != "environment" and ref not in body_names:
                bad(("joints", name, "bodies", i), _unknown("body", ref, body_names | {"environment"}))
        if joint.bodies[0] == joint.bodies[1]:
            bad(("joints", name, "bodies"), "a joint needs two different bodies")
        for i, ref in enumerate(joint.bodies):
            if ref in body_names and model.bodies.get(ref) and model.bodies[ref].motion == "static" and i == 0:
                bad(("joints", name, "bodies", 0), f"body `{ref}` is static; a joint's first body must move")
    for i, pair in enumerate(model.surfaces):
        for j, ref in enumerate(pair.bodies):
            if ref not in body_names and ref not in group_names:
                bad(("surfaces", i, "bodies", j), _unknown("body", ref, body_names | group_names))
    sound_lengths: dict[str, float] = {}
    root = base_dir.resolve()
    for name, rel in model.sounds.items():
        try:
            target = (base_dir / rel).resolve()
        except (OSError, RuntimeError) as exc:  # RuntimeError: a symlink loop (Python 3.11's resolve)
            bad(("sounds", name), f"expected a WAV file at {rel!r}: cannot follow its path ({exc})")
            continue
        if not target.is_relative_to(root):
            bad(("sounds", name), f"the sound file must be inside the scenario's folder {root}; found {rel!r}")
            continue
        try:
            sound_lengths[name] = read_info(target).length
        except SoundFileError as exc:
            bad(("sounds", name), f"expected a WAV file at {rel!r}: {exc}")
    nodes = model.collisions.nodes
    for node_name, node in nodes.items():
        if node.body not in body_names:
            bad(("collisions", "nodes", node_name, "body"), _unknown("body", node.body, body_names))
        for k, solid in enumerate(node.all_solids()):
            if solid.polygon is not None:
                problem = polygon_problem(solid.polygon)
                if problem:
                    tail: tuple[str | int, ...] = ("solids", k) if k < len(node.solids) else ("polygon",)
                    bad(("collisions", "nodes", node_name, *tail), problem)
    for i, ref in enumerate(model.collisions.from_):
        if ref not in nodes:
            bad(("collisions", "from", i), _unknown("collision node", ref, nodes))
        elif any(s.sphere is None for s in nodes[ref].all_solids()):
            bad(
                ("collisions", "from", i),
                f"collider `{ref}` must hold only spheres (Panda3D from-solids supported here: sphere)",
            )
    for i, ref in enumerate(model.collisions.contacts_from):
        if ref not in body_names:
            bad(("collisions", "contacts_from", i), _unknown("body", ref, body_names))
    for ival, definition in model.intervals.items():
        for step, path in walk_steps(definition, ("intervals", ival)):
            if step.lerp is not None:
                ref = step.lerp.body
                if ref not in body_names:
                    bad(path + ("lerp", "body"), _unknown("body", ref, body_names))
                elif model.bodies.get(ref) is not None and model.bodies[ref].motion != "kinematic":
                    bad(
                        path + ("lerp", "body"),
                        f"intervals move kinematic bodies; `{ref}` is {model.bodies[ref].motion}",
                    )
            if step.sound is not None:
                ref = step.sound if isinstance(step.sound, str) else step.sound.sound
                if ref not in model.sounds:
                    bad(path + ("sound",), _unknown("sound", ref, model.sounds))
            if step.interval is not None and step.interval not in model.intervals:
                bad(path + ("interval",), _unknown("interval", step.interval, model.intervals))
    if not model.bodies and not model.robots:
        bad(("bodies",), "a scenario needs at least one body: give `bodies` (or `robots`, whose links are bodies)")
    check_interval_cycles(model, bad)
    _check_actions(model, bad, body_names, sound_lengths, robots)
    _check_expressions(model, bad, body_names | group_names, robots)
    _check_events(model, bad, set(robot_links(robots)))
    _check_servos(model, bad, robots)
    check_initial(model, bad, robots)
    check_handlers(model, bad, possible_events(model))
    check_times(model, bad)
    check_backend_options(model, bad)
    if issues:
        raise ScenarioValidationError(issues)


_INTERVAL_ACTIONS: dict[type, str] = {
    Act.StartAction: "start",
    Act.PauseAction: "pause",
    Act.ResumeAction: "resume",
    Act.FinishAction: "finish",
    Act.LoopAction: "loop",
}


def _check_actions(
    model: Scenario, bad: Any, body_names: set[str], sounds: dict[str, float], robots: Mapping[str, ModelDesc]
) -> None:
    for action, path in all_actions(model):
        kind = _INTERVAL_ACTIONS.get(type(action))
        if kind is not None and getattr(action, kind) not in model.intervals:
            bad(path + (kind,), _unknown("interval", getattr(action, kind), model.intervals))
        if isinstance(action, Act.SetAction | Act.CalcAction):
            field = "set" if isinstance(action, Act.SetAction) else "calc"
            for var in getattr(action, field):
                if var not in model.state:
                    bad(path + (field, var), _unknown("state variable", var, model.state), True)
        if isinstance(action, Act.PlaySoundAction | Act.StopSoundAction):
            field = "play_sound" if isinstance(action, Act.PlaySoundAction) else "stop_sound"
            ref = getattr(action, field)
            if ref not in model.sounds:
                bad(path + (field,), _unknown("sound", ref, model.sounds))
        if isinstance(action, Act.MotorAction):
            check_motor(model, bad, path, action.motor.joint, robots)
        if isinstance(action, Act.DriveAction):
            check_motor(model, bad, path, action.drive.joint, robots, "drive")
        if isinstance(action, Act.ControlAction):
            names = [f"{r}.{a.name}" for r, desc in robots.items() for a in desc.actuators]
            if action.control.actuator not in names:
                bad(path + ("control", "actuator"), _unknown("actuator (MJCF <actuator>)", action.control.actuator,
                                                             names))  # fmt: skip
        if isinstance(action, Act.ForceAction | Act.ImpulseAction | Act.ApplyAction):
            field = "force" if isinstance(action, Act.ForceAction) else "impulse"
            field = "apply" if isinstance(action, Act.ApplyAction) else field
            cmd = getattr(action, field)
            if cmd.body not in body_names:
                bad(path + (field, "body"), _unknown("body", cmd.body, body_names))
        if isinstance(action, Act.ResetAction):
            ref = action.reset if isinstance(action.reset, str) else action.reset.body
            held = {b for j in model.joints.values() for b in j.bodies} | set(jointed_links(robots))
            if ref not in body_names:
                bad(path + ("reset",), _unknown("body", ref, body_names))
            elif ref in held:
                bad(path + ("reset",), f"body `{ref}` is held by a joint; only free bodies can be reset")


def expressions_in(model: Scenario) -> Iterator[tuple[str, Path]]:
    """Every expression text in the scenario, with where it is."""
    for action, path in all_actions(model):
        if isinstance(action, Act.IfAction):
            yield action.if_, path + ("if",)
        if isinstance(action, Act.CalcAction):
            for var, text in action.calc.items():
                yield text, path + ("calc", var)
        if isinstance(action, Act.ApplyAction) and action.apply.until is not None:
            yield action.apply.until, path + ("apply", "until")
        if isinstance(action, Act.DriveAction):
            yield from drive_expressions(action.drive, path + ("drive",))
        if isinstance(action, Act.ControlAction) and isinstance(action.control.ctrl, str):
            yield action.control.ctrl, path + ("control", "ctrl")
    for jname, joint in model.joints.items():
        if joint.drive is not None:
            yield from drive_expressions(joint.drive, ("joints", jname, "drive"))
    for rname, robot in model.robots.items():
        for jname, rjoint in robot.joints.items():
            if rjoint.drive is not None:
                yield from drive_expressions(rjoint.drive, ("robots", rname, "joints", jname, "drive"))
        for aname, control in robot.actuators.items():
            if isinstance(control.ctrl, str):
                yield control.ctrl, ("robots", rname, "actuators", aname, "ctrl")
    for name, trigger in model.triggers.items():
        yield trigger.when, ("triggers", name, "when")
    for i, a in enumerate(model.assertions):
        for field in (
            "value",
            "check",
            "always",
            "never",
            "eventually",
            "max_of",
            "min_of",
            "becomes",
            "near",
            "min",
            "max",
            "tol",
            "time_tol",
        ):
            value = getattr(a, field, None)
            alias = {"max_of": "max", "min_of": "min"}.get(field, field)
            if isinstance(value, dict):
                yield from ((t, ("assertions", i, alias, k)) for k, t in value.items() if isinstance(t, str))
            elif isinstance(value, str):
                yield value, ("assertions", i, alias)


def drive_expressions(drive: Drive, path: Path) -> Iterator[tuple[str, Path]]:
    """The expressions of a joint command (its targets and torque written as text)."""
    for field in ("position", "rate", "torque"):
        value = getattr(drive, field)
        if isinstance(value, str):
            yield value, path + (field,)


def _check_expressions(model: Scenario, bad: Any, owners: set[str], robots: Mapping[str, ModelDesc]) -> None:
    valid = set(readable_names(model, robots))
    known = {
        "contact": ("body", owners),
        "playing": ("interval", set(model.intervals)),
        "count": ("event (it can never happen)", possible_events(model)),
    }
    for text, path in expressions_in(model):
        try:
            expr = compile_expression(text)
        except ExpressionError as exc:
            bad(path, str(exc))
            continue
        problems = [check_name(name, valid) for name in sorted(expr.names)]
        for func, args in sorted(expr.call_args):
            kind, names = known[func]
            problems += [f"{func}(): {_unknown(kind, a, names)}" for a in args if a not in names]
        first = next((p for p in problems if p), None)
        if first:
            bad(path, first)


def _check_servos(model: Scenario, bad: Any, robots: Mapping[str, ModelDesc]) -> None:
    """A servo target written as an expression reads names that exist."""
    valid = set(readable_names(model, robots))
    for rname, robot in model.robots.items():
        for jname, joint in robot.joints.items():
            if joint.servo is None:
                continue
            if joint.servo.gain * model.world.dt > 1.0:
                bad(("robots", rname, "joints", jname, "servo", "gain"), f"expected gain x dt <= 1 (the servo's error "
                    f"is multiplied by 1 - gain dt each step; above 1 it overshoots), found {joint.servo.gain} x "
                    f"{model.world.dt} = {joint.servo.gain * model.world.dt:.3g}")
            path = ("robots", rname, "joints", jname, "servo", "target")
            if not isinstance(joint.servo.target, str):
                continue
            try:
                expr = compile_expression(joint.servo.target)
            except ExpressionError as exc:
                bad(path, str(exc))
                continue
            first = next((p for p in (check_name(n, valid) for n in sorted(expr.names)) if p), None)
            if first:
                bad(path, first)


def _check_events(model: Scenario, bad: Any, links: set[str]) -> None:
    events = possible_events(model)
    for i, a in enumerate(model.assertions):
        if isinstance(a, A.EventAssertion):
            for field in ("event", "before", "after"):
                name = getattr(a, field)
                if name is not None and name not in events:
                    bad(("assertions", i, field), _unknown("event (it can never happen)", name, events))
        if isinstance(a, A.SoundAssertion) and a.sound not in model.sounds:
            bad(("assertions", i, "sound"), _unknown("sound", a.sound, model.sounds))
        if isinstance(a, A.ContactAssertion):
            names = {b.name for b in expand_bodies(model)} | links
            for j, ref in enumerate(a.contact):
                if ref not in names:
                    bad(("assertions", i, "contact", j), _unknown("body", ref, names))
