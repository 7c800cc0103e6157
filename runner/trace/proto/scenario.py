"""The per-trace messages ``physics_scenarios.Bodies``, ``Joints`` and ``State``: one field per body, joint
or state variable, named after it, so that Foxglove's message paths read ``/bodies.box.vel.z``,
``/joints.slider.position`` and ``/state.door_open``.

They are built with google.protobuf's descriptor API (``FileDescriptorProto`` → ``DescriptorPool`` →
message classes) in a pool of their own per trace, since two traces in one process may name different
bodies. State is a file of its own, built when the first step brings the variables' values (their types
are those of the initial values). Names are the language's identifiers (``[A-Za-z_][A-Za-z0-9_]*``),
valid protobuf field names as they are; ``json_name`` is set to the name itself so no consumer camel-cases
it. A robot's links and joints (``arm.link_7``, docs/robots.md) are fields of a nested message per robot,
so the paths read ``/bodies.arm.link_7.vel.z`` as the expressions do; a member whose name the model file
spells otherwise than as an identifier (``8``) has the field :func:`reports.trace_format.field_name` gives
(``/joints.arm._8.position``). Traces without robots are unchanged.
A world of more than 8,000 bodies (or joints) has a message per 8,000, on /bodies/2, ... (protobuf's limit on
one message, :data:`reports.trace_format.FIELDS_PER_MESSAGE`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from reports import trace_format as tf
from runner.trace.proto import physics_scenarios_pb2 as base

__all__ = ["PACKAGE", "ScenarioMessages", "field_of", "part_name", "scenario_messages", "state_field_type",
           "with_state", "sensors_class"]

PACKAGE = "physics_scenarios"
FILE_NAME = "physics_scenarios_scenario.proto"
STATE_FILE_NAME = "physics_scenarios_state.proto"
SENSORS_FILE_NAME = "physics_scenarios_sensors.proto"
_F = descriptor_pb2.FieldDescriptorProto

#: state field types, by the Python type of the variable's initial value
_STATE_TYPES = {bool: _F.TYPE_BOOL, int: _F.TYPE_DOUBLE, float: _F.TYPE_DOUBLE, str: _F.TYPE_STRING}


def state_field_type(value: Any) -> str:
    """"bool", "double" or "string": the field type of a state variable that starts at ``value``."""
    kind = _STATE_TYPES.get(type(value), _F.TYPE_STRING)
    return {_F.TYPE_BOOL: "bool", _F.TYPE_DOUBLE: "double"}.get(kind, "string")


@dataclass(frozen=True)
class ScenarioMessages:
    """The message classes of one trace: ``bodies`` and ``joints``, one class per part of their names
    (:func:`reports.trace_format.message_parts`: one part up to 8,000); ``state`` once its types are known."""

    bodies: tuple[Any, ...]
    joints: tuple[Any, ...]
    body_parts: tuple[list[str], ...]  # the names each class of ``bodies`` holds
    joint_parts: tuple[list[str], ...]
    state: Any = None
    state_types: Mapping[str, str] = field(default_factory=dict)  # variable -> "bool" | "double" | "string"


def _message(
    file: descriptor_pb2.FileDescriptorProto, name: str, fields: Sequence[tuple[str, int, str | None]]
) -> None:
    msg = file.message_type.add(name=name)
    _fields(msg, fields)


def _fields(msg: descriptor_pb2.DescriptorProto, fields: Sequence[tuple[str, int, str | None]]) -> None:
    for number, (field_name, kind, type_name) in enumerate(fields, start=1):
        f = msg.field.add(name=field_name, json_name=field_name, number=number, type=kind, label=_F.LABEL_OPTIONAL)
        if type_name is not None:
            f.type_name = type_name


def _grouped(file: descriptor_pb2.FileDescriptorProto, name: str, names: Sequence[str], type_name: str) -> None:
    """Message ``name`` with a ``type_name`` field per plain name and, per robot (the part before a dot), a
    field of a nested message ``Robot_<robot>`` holding its members, at the robot's first member's place."""
    msg = file.message_type.add(name=name)
    fields: list[tuple[str, int, str | None]] = []
    members: dict[str, list[str]] = {}
    for n in names:
        group, dot, leaf = n.partition(".")
        if not dot:
            fields.append((n, _F.TYPE_MESSAGE, type_name))
            continue
        if group not in members:
            members[group] = []
            fields.append((group, _F.TYPE_MESSAGE, f".{PACKAGE}.{name}.Robot_{group}"))
        members[group].append(tf.field_name(leaf))
    _fields(msg, fields)
    for group, leaves in members.items():
        _fields(msg.nested_type.add(name=f"Robot_{group}"), [(leaf, _F.TYPE_MESSAGE, type_name) for leaf in leaves])


def field_of(msg: Any, name: str) -> Any:
    """The field of ``msg`` for a name, a robot member's (``arm.link_7``) through its robot's message."""
    group, dot, leaf = name.partition(".")
    return getattr(getattr(msg, group), tf.field_name(leaf)) if dot else getattr(msg, name)


def _classes(files: Sequence[descriptor_pb2.FileDescriptorProto], names: Sequence[str], with_base: bool) -> list[Any]:
    pool = descriptor_pool.DescriptorPool()
    try:
        if with_base:
            pool.AddSerializedFile(base.DESCRIPTOR.serialized_pb)
        for file in files:
            pool.Add(file)
        return [message_factory.GetMessageClass(pool.FindMessageTypeByName(f"{PACKAGE}.{n}")) for n in names]
    except TypeError as exc:  # protobuf's error for a descriptor it refuses (duplicate or bad names)
        raise ValueError(f"cannot build the trace's messages for these names: {exc}") from exc


def part_name(message: str, part: int) -> str:
    """``Bodies``, ``Bodies_2``, ...: the message of part ``part`` (from 0) of /bodies or /joints."""
    return message if part == 0 else f"{message}_{part + 1}"


def scenario_messages(bodies: Sequence[str], joints: Sequence[str]) -> ScenarioMessages:
    """``physics_scenarios.Bodies`` and ``Joints`` for a scenario's bodies and joints (CompiledWorld order),
    one message per part of the names (``Bodies_2`` ... beyond 8,000, each part in a file of its own, so that
    a channel's schema holds its part only). Raises ``ValueError`` for names protobuf refuses."""
    body_parts, joint_parts = tf.message_parts(bodies), tf.message_parts(joints)
    motion = f".{base.BodyMotion.DESCRIPTOR.full_name}"
    joint = f".{base.JointState.DESCRIPTOR.full_name}"
    files: list[descriptor_pb2.FileDescriptorProto] = []
    names: dict[str, list[str]] = {"Bodies": [], "Joints": []}
    for k in range(max(len(body_parts), len(joint_parts))):
        file = descriptor_pb2.FileDescriptorProto(
            name=FILE_NAME if k == 0 else FILE_NAME.replace(".proto", f"_{k + 1}.proto"),
            package=PACKAGE, syntax="proto3", dependency=[base.DESCRIPTOR.name],
        )  # fmt: skip
        for message, parts, type_name in (("Bodies", body_parts, motion), ("Joints", joint_parts, joint)):
            if k < len(parts):
                names[message].append(part_name(message, k))
                _grouped(file, names[message][-1], parts[k], type_name)
        files.append(file)
    classes = _classes(files, names["Bodies"] + names["Joints"], with_base=True)
    return ScenarioMessages(tuple(classes[: len(body_parts)]), tuple(classes[len(body_parts) :]), tuple(body_parts),
                            tuple(joint_parts))  # fmt: skip


def with_state(messages: ScenarioMessages, state: Mapping[str, Any]) -> ScenarioMessages:
    """``messages`` plus ``physics_scenarios.State`` for variables starting at ``state`` (name -> value):
    a bool, double or string field each, by the type of its value."""
    types = {name: state_field_type(value) for name, value in state.items()}
    kinds = {"bool": _F.TYPE_BOOL, "double": _F.TYPE_DOUBLE, "string": _F.TYPE_STRING}
    file = descriptor_pb2.FileDescriptorProto(name=STATE_FILE_NAME, package=PACKAGE, syntax="proto3")
    _message(file, "State", [(name, kinds[kind], None) for name, kind in types.items()])
    (state_class,) = _classes([file], ("State",), with_base=False)
    return replace(messages, state=state_class, state_types=types)


def sensors_class(fields: Sequence[str]) -> Any:
    """``physics_scenarios.Sensors``: a double field per sensor quantity (its ``tf.sensor_field``), in order."""
    file = descriptor_pb2.FileDescriptorProto(name=SENSORS_FILE_NAME, package=PACKAGE, syntax="proto3")
    _message(file, "Sensors", [(name, _F.TYPE_DOUBLE, None) for name in fields])
    (cls,) = _classes([file], ("Sensors",), with_base=False)
    return cls
