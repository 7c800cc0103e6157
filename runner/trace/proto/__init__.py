"""The trace's protobuf messages: the project's own (``physics_scenarios.proto``, generated code beside it),
the per-trace ones built from a scenario's names (:mod:`runner.trace.proto.scenario`), and the schema
records an MCAP file carries for them (a serialised ``FileDescriptorSet`` per message type)."""

from __future__ import annotations

from typing import Any

from mcap_protobuf.schema import build_file_descriptor_set

from runner.trace.proto.physics_scenarios_pb2 import (
    BodyMotion,
    ContactPair,
    Contacts,
    Event,
    JointState,
    KeyValue,
    Sound,
    Vector3,
    Verdict,
    Verdicts,
)

__all__ = [
    "BodyMotion",
    "ContactPair",
    "Contacts",
    "Event",
    "JointState",
    "KeyValue",
    "Sound",
    "Vector3",
    "Verdict",
    "Verdicts",
    "schema_data",
]


def schema_data(message_class: Any) -> bytes:
    """The schema record's data for ``message_class``: its file and every file it imports, as a
    serialised ``google.protobuf.FileDescriptorSet`` (what Foxglove, Rerun and mcap-protobuf read)."""
    return bytes(build_file_descriptor_set(message_class).SerializeToString())
