"""The quantities a scenario's assertions read, resolved against its compiled world.

Each expression an assertion evaluates (``value``, ``check``, ``always``, ``never``, ``eventually``,
``becomes``, ``max``, ``min``, and ``near``/``min``/``max`` when they are expressions) names quantities;
each name becomes one or more *quantities*, in the forms the trace's series are named by
(:meth:`reports.trace_reader.Trace.series`), plus three derived ones:

* ``<body>.pos.z``, ``<body>.vel.x``, ``<body>.angvel.y``, ``<body>.quat.w``: a component;
* ``<body>.speed`` (norm of the velocity) and ``<body>.energy`` (J, docs/language.md);
* ``<joint>.position``, ``<joint>.velocity``, ``<joint>.force``; ``state.<variable>``;
* ``contact(<a>, <b>)``: the normal force between two bodies (a ``contact`` assertion or call);
* a sensor quantity (``shoulder.reaction.torque.y``, ``box.kinetic_energy``, ``hand.pinch site.pos.z``):
  as the trace's /sensors names it (``Program.sensors``).

An array's name stands for every copy (``max(crate.pos.z)`` reads ``crate_0.pos.z`` ... ``crate_4.pos.z``).
Time, constants and parameters are not quantities. The list is written into each trace's ``scenario``
metadata (``asserted``), so the viewers' exports plot what a scenario asserts from the trace alone.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from runner.compile.program import Program
from runner.language import model_assertions as A
from runner.language.expressions import ExpressionError, compile_expression
from runner.language.names import split_owner

__all__ = ["asserted_quantities"]

#: the fields of an assertion that always hold an expression
_EXPRESSIONS = ("value", "check", "always", "never", "eventually", "becomes", "max_of", "min_of")
#: fields that hold an expression when they are text (a number otherwise); times are not quantities
_MAYBE_EXPRESSIONS = ("near", "min", "max")
_BODY_FIELDS = {"pos": "xyz", "vel": "xyz", "angvel": "xyz", "quat": "wxyz"}
_JOINT_FIELDS = ("position", "velocity", "force")


def _texts(assertion: Any) -> list[str]:
    out = [t for f in _EXPRESSIONS if isinstance(t := getattr(assertion, f, None), str)]
    if isinstance(assertion, A.ValueAssertion | A.ExtremumBase):
        out += [t for f in _MAYBE_EXPRESSIONS if isinstance(t := getattr(assertion, f, None), str)]
    return out


def _resolve(
    name: str, bodies: set[str], joints: set[str], groups: dict[str, list[str]], state: set[str], sensors: set[str]
) -> list[str]:
    """The quantities one dotted name reads (nothing for time, constants, parameters and unknown names)."""
    if name in sensors:  # a sensor quantity (docs/language.md "Sensors"): on the trace's /sensors
        return [name]
    head, rest = split_owner(name, bodies | joints)  # a robot's link or joint: `arm.link_7.pos.z`
    if head in groups and all(f"{b}.{rest}" in sensors for b in groups[head]):
        return [f"{b}.{rest}" for b in groups[head]]
    if head == "state":
        return [name] if rest in state else []
    if head in joints:
        return [f"{head}.{rest}"] if rest in _JOINT_FIELDS else []
    members = [head] if head in bodies else groups.get(head, [])
    field, _, component = rest.partition(".")
    if rest in ("speed", "energy"):
        return [f"{b}.{rest}" for b in members]
    if field in _BODY_FIELDS and component and component in _BODY_FIELDS[field]:
        return [f"{b}.{field}.{component}" for b in members]
    return []


def contact_quantity(a: str, b: str) -> str:
    return f"contact({a}, {b})"


def asserted_quantities(program: Program, assertions: Iterable[Any] | None = None) -> list[str]:
    """Every quantity the assertions read (default: the scenario's), each once, in assertion order."""
    bodies = {b.name for b in program.world.bodies}
    joints = {j.name for j in program.world.joints}
    state = set(program.loaded.model.state)
    sensors = set(program.sensors)
    out: dict[str, None] = {}
    for assertion in program.loaded.model.assertions if assertions is None else assertions:
        if isinstance(assertion, A.ContactAssertion):
            out[contact_quantity(*assertion.contact)] = None
            continue
        for text in _texts(assertion):
            try:
                expression = compile_expression(text)
            except ExpressionError:
                continue  # refused when the scenario was checked; nothing to plot
            for name in sorted(expression.names):
                out.update(dict.fromkeys(_resolve(name, bodies, joints, program.groups, state, sensors)))
            for function, args in sorted(expression.call_args):
                if function == "contact" and len(args) == 2:
                    out[contact_quantity(args[0], args[1])] = None
    return list(out)
