"""The trace's protobuf messages: the project's own (``physics_scenarios.proto``, generated code beside it),
the per-trace ones built from a scenario's names (:mod:`runner.trace.proto.scenario`), and the schema
records an MCAP file carries for them (a serialised ``FileDescriptorSet`` per message type)."""

from __future__ import annotations

from typing import Any

from google.protobuf.descriptor import FileDescriptor
from google.protobuf.descriptor_pb2 import FileDescriptorSet

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
    serialised ``google.protobuf.FileDescriptorSet`` (what Foxglove, Rerun and mcap-protobuf read), each
    file after the files it imports (depth first, in import order, each once), as mcap-protobuf orders them.
    Built here rather than by ``mcap_protobuf.schema``, whose import brings mcap's writer and its
    compressors (about 25 ms of a run's start-up, which writes through the Foxglove SDK)."""
    files = FileDescriptorSet()
    seen: set[str] = set()

    def add(file: FileDescriptor) -> None:
        for dependency in file.dependencies:
            if dependency.name not in seen:
                seen.add(dependency.name)
                add(dependency)
        file.CopyToProto(files.file.add())

    add(message_class.DESCRIPTOR.file)
    return bytes(files.SerializeToString())
