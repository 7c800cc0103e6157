"""What a scenario reads that an engine must measure for it: the joints whose reaction it reads.

An engine computes a joint's reaction only where asked (a force/torque sensor, a pass over the tree:
docs/semantics.md, "Sensors"), so the compiler lists the joints whose ``<joint>.reaction...`` an
expression reads (assertions, conditions, triggers, handlers, servo targets) in ``CompiledWorld.reaction_joints``.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from backends.types import CompiledWorld
from runner.language.expressions import ExpressionError, compile_expression
from runner.language.model import Scenario
from runner.language.names import FRAME_FIELDS, REACTION_FIELDS, split_owner
from runner.language.refs import expressions_in

__all__ = ["reaction_joints", "sensor_quantities"]


def _texts(model: Scenario) -> Iterator[str]:
    yield from (text for text, _ in expressions_in(model))
    for robot in model.robots.values():
        for joint in robot.joints.values():
            if joint.servo is not None and isinstance(joint.servo.target, str):
                yield joint.servo.target


def reaction_joints(model: Scenario, joints: Sequence[str]) -> tuple[str, ...]:
    """The joints (of ``joints``, in that order) whose reaction an expression of ``model`` reads."""
    known = set(joints)
    read: set[str] = set()
    for text in _texts(model):
        try:
            names = compile_expression(text).names
        except ExpressionError:
            continue  # refused when the scenario was checked
        for name in names:
            head, rest = split_owner(name, known)
            if head in known and rest.partition(".")[0] in REACTION_FIELDS:
                read.add(head)
    return tuple(j for j in joints if j in read)



#: the body quantities only the runner computes (runner.sim.body_quantities): what /sensors carries for bodies
_BODY_SENSORS = ("kinetic_energy", "momentum", "angmom", "angmom_origin", "angvel_body")


def sensor_quantities(
    model: Scenario, world: CompiledWorld, groups: dict[str, list[str]], frames: set[str]
) -> list[str]:
    """The sensor quantities (docs/language.md "Sensors") an expression of ``model`` reads, each for one body,
    joint or frame (an array's name: every copy), sorted: what the trace's /sensors carries."""
    bodies = {b.name for b in world.bodies}
    joints = {j.name for j in world.joints}
    members = bodies | joints | frames
    out: set[str] = set()
    for text in _texts(model):
        try:
            names = compile_expression(text).names
        except ExpressionError:
            continue
        for name in names:
            head, rest = split_owner(name, members)
            field = rest.partition(".")[0]
            if head in joints and field in REACTION_FIELDS:
                out.add(name)
            elif head in frames and field in FRAME_FIELDS:
                out.add(name)
            elif field in _BODY_SENSORS and (head in bodies or head in groups):
                out.update(f"{b}.{rest}" for b in ([head] if head in bodies else groups[head]))
    return sorted(out)
