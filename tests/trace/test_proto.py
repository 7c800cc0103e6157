"""The committed .proto and its generated code (runner/trace/proto/) say the same thing.

`make proto` regenerates the code with protoc; this test reads the .proto's message and field lines and
compares them with the descriptor compiled into physics_scenarios_pb2.py, so an edit to one without the
other fails here.
"""

from __future__ import annotations

import re
from pathlib import Path

from google.protobuf.descriptor import FieldDescriptor

from runner.trace.proto import physics_scenarios_pb2 as generated

PROTO = Path(generated.__file__).with_suffix("").with_name("physics_scenarios.proto")
_TYPES = {
    FieldDescriptor.TYPE_DOUBLE: "double", FieldDescriptor.TYPE_FIXED32: "fixed32",
    FieldDescriptor.TYPE_UINT32: "uint32", FieldDescriptor.TYPE_STRING: "string", FieldDescriptor.TYPE_BOOL: "bool",
}  # fmt: skip


def _declared() -> dict[str, list[tuple[str, str, str, int]]]:
    """{message: [(label, type, name, number)]} from the .proto text (comments removed)."""
    text = re.sub(r"//[^\n]*", "", PROTO.read_text())
    out: dict[str, list[tuple[str, str, str, int]]] = {}
    for name, body in re.findall(r"message\s+(\w+)\s*\{([^}]*)\}", text):
        fields = re.findall(r"(repeated\s+|optional\s+)?([\w.]+)\s+(\w+)\s*=\s*(\d+)\s*;", body)
        out[name] = [(label.strip(), kind, fname, int(number)) for label, kind, fname, number in fields]
    return out


def _compiled() -> dict[str, list[tuple[str, str, str, int]]]:
    out = {}
    for name, desc in generated.DESCRIPTOR.message_types_by_name.items():
        fields = []
        for f in desc.fields:
            repeated = f.is_repeated if hasattr(f, "is_repeated") else f.label == FieldDescriptor.LABEL_REPEATED
            label = "repeated" if repeated else "optional" if f.has_presence and f.message_type is None else ""
            kind = f.message_type.name if f.message_type is not None else _TYPES[f.type]
            fields.append((label, kind, f.name, f.number))
        out[name] = fields
    return out


def test_the_generated_code_matches_the_proto_file() -> None:
    declared = _declared()
    assert declared, "no message found in the .proto"
    assert declared == _compiled()
    assert generated.DESCRIPTOR.package == "physics_scenarios"
    assert 'package physics_scenarios;' in PROTO.read_text() and 'syntax = "proto3";' in PROTO.read_text()
