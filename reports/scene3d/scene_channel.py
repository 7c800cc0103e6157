"""The trace's ``foxglove.SceneUpdate`` messages, decoded by the channel's declared message encoding.

:mod:`reports.trace_reader` keeps the per-step data and leaves the scene to Foxglove; the pictures need
it too (collision solids, scale changes). This reads only that channel, found by its well-known schema
name, so it does not depend on how the project's own channels are encoded: ``json`` messages are parsed
as JSON, ``protobuf`` ones with the FileDescriptorSet the channel's schema carries (google.protobuf's
descriptor pool and message factory) and turned into dicts with Foxglove's field names. An index lets
the seeking reader skip every chunk without a scene message; a file without one (a cut-off partial
trace) is read from the start and reading stops at the first damaged record, keeping what came before.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap.records import Schema

from reports import trace_format as tf
from reports.trace_chunks import read_damage

__all__ = ["SCENE_SCHEMA", "read_scene_updates"]

SCENE_SCHEMA = "foxglove.SceneUpdate"
_TOPICS = [tf.TOPIC_SCENE, tf.TOPIC_SCENE_COLLISION, tf.TOPIC_CONTACT_POINTS]

Decoder = Callable[[bytes], Mapping[str, Any]]


def _protobuf_decoder(schema: Schema) -> Decoder:
    from google.protobuf import descriptor_pb2, descriptor_pool, json_format, message_factory
    from google.protobuf.message import DecodeError

    files = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    pending = list(files.file)
    while pending:  # add each file after the files it depends on
        added = [f for f in pending if all(_has_file(pool, d) for d in f.dependency)]
        if not added:
            raise ValueError(f"the schema {schema.name} does not carry every file it depends on")
        for f in added:
            pool.Add(f)
        pending = [f for f in pending if f not in added]
    cls = message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))

    def decode(data: bytes) -> Mapping[str, Any]:
        try:
            message = cls.FromString(data)
        except DecodeError as exc:
            raise ValueError(f"not a {schema.name} message: {exc}") from exc
        return json_format.MessageToDict(message, preserving_proto_field_name=True)

    return decode


def _has_file(pool: Any, name: str) -> bool:
    try:
        pool.FindFileByName(name)
    except KeyError:
        return False
    return True


def _decoder(schema: Schema | None, message_encoding: str) -> Decoder | None:
    if schema is None or schema.name != SCENE_SCHEMA:
        return None
    if message_encoding == "json":
        return json.loads
    if message_encoding == "protobuf":
        return _protobuf_decoder(schema)
    return None


def read_scene_updates(path: Path) -> list[tuple[float, Mapping[str, Any]]]:
    """(simulated time, SceneUpdate as a dict) of every scene message in the trace (/scene,
    /scene/collision and the contact arrows of /contact_points), in time order;
    empty when the file has no scene channel in an encoding this module decodes."""
    out: list[tuple[float, Mapping[str, Any]]] = []
    decoders: dict[int, Decoder | None] = {}
    ends: tuple[type[Exception], ...] = (OSError, KeyError, *read_damage())
    try:
        with open(path, "rb") as f:
            reader = make_reader(f, validate_crcs=True)
            for schema, channel, message in reader.iter_messages(topics=_TOPICS):
                if channel.id not in decoders:
                    decoders[channel.id] = _decoder(schema, channel.message_encoding)
                decode = decoders[channel.id]
                if decode is not None:
                    out.append((message.log_time / 1e9, decode(message.data)))
    except ends:
        pass  # a damaged end (partial trace): keep what was read; no channel: the metadata shapes serve
    out.sort(key=lambda item: item[0])
    return out
