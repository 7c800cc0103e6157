"""Decoding a trace's messages (format 2, protobuf) into the reader's records.

Message classes come from the schema records in the file itself, through mcap-protobuf's decoder factory:
the reader needs none of the writer's code, and reads any file whose channels carry these schemas.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from google.protobuf.message import DecodeError
from mcap.records import Schema
from mcap_protobuf.decoder import DecoderFactory

from reports import trace_format as tf

__all__ = ["Decoded", "MessageDecoder", "UnreadableMessage"]

_VERDICT_NUMBERS = ("time", "value", "target", "tolerance")
_FIELD_TYPE_BOOL, _FIELD_TYPE_STRING = 8, 9  # google.protobuf.FieldDescriptor.TYPE_*



def _member(msg: Any, name: str) -> Any:
    """A body's or joint's field; a robot's link or joint (`arm.link_7`) is in its robot's nested message."""
    group, dot, leaf = name.partition(".")
    return getattr(getattr(msg, group, None), tf.field_name(leaf), None) if dot else getattr(msg, name, None)

class UnreadableMessage(ValueError):
    """A message that its channel's schema does not decode."""


@dataclass
class Decoded:
    """What the messages held, as lists; the reader turns them into arrays once at the end."""

    tf_times: list[float] = field(default_factory=list)
    poses: list[list[float]] = field(default_factory=list)  # per step: body-major x y z, w x y z
    motion_times: list[float] = field(default_factory=list)
    motions: list[list[float]] = field(default_factory=list)  # per step: body-major vel xyz, angvel xyz
    joint_times: list[float] = field(default_factory=list)
    joint_rows: list[list[float]] = field(default_factory=list)
    state_times: list[float] = field(default_factory=list)
    state: dict[str, list[Any]] = field(default_factory=dict)
    sensor_times: list[float] = field(default_factory=list)
    sensors: dict[str, list[float]] = field(default_factory=dict)  # by field (tf.sensor_field)
    contacts: list[tuple[float, list[dict[str, Any]]]] = field(default_factory=list)
    events: list[tuple[float, str, str, dict[str, Any]]] = field(default_factory=list)
    logs: list[tuple[float, str, str, str]] = field(default_factory=list)
    sounds: list[tuple[float, str, str, float, float]] = field(default_factory=list)
    verdicts: list[tuple[float, dict[str, Any]]] = field(default_factory=list)


class MessageDecoder:
    """Decodes messages channel by channel; ``bodies`` and ``joints`` name the rows' order."""

    def __init__(self, bodies: list[str], joints: list[str]) -> None:
        self.bodies = bodies
        self.joints = joints
        self._index = {name: i for i, name in enumerate(bodies)}
        #: topic -> (first index, names) of each part of /bodies and /joints (one part up to 8,000 names)
        self._parts = {**tf.parts_by_topic(tf.TOPIC_BODIES, bodies), **tf.parts_by_topic(tf.TOPIC_JOINTS, joints)}
        self._factory = DecoderFactory()
        self._decoders: dict[int, Callable[[bytes], Any]] = {}
        self.out = Decoded()

    def _decode(self, schema: Schema, message_encoding: str, data: bytes) -> Any:
        decode = self._decoders.get(schema.id)
        if decode is None:
            found = self._factory.decoder_for(message_encoding, schema)
            if found is None:
                raise UnreadableMessage(f"no protobuf decoder for schema {schema.name!r} ({schema.encoding})")
            decode = self._decoders[schema.id] = found
        try:
            return decode(data)
        except (DecodeError, RuntimeError, ValueError) as exc:
            raise UnreadableMessage(f"a {schema.name} message does not decode: {exc}") from exc

    def add(self, topic: str, schema: Schema | None, message_encoding: str, t: float, data: bytes) -> None:
        if schema is None:
            return
        part = self._parts.get(topic)
        if part is not None:  # /bodies, /joints and their further parts
            is_bodies = topic.startswith(tf.TOPIC_BODIES)
            self._part(t, self._decode(schema, message_encoding, data), part, is_bodies)
            return
        handler = self._handlers.get(topic)
        if handler is None:
            return  # /scene and /audio are for viewers; unknown topics are someone else's
        handler(self, t, self._decode(schema, message_encoding, data))

    # ---- per channel ------------------------------------------------------------------------------
    def _tf(self, t: float, msg: Any) -> None:
        row = [math.nan] * (7 * len(self.bodies))
        index = self._index
        for frame in msg.transforms:
            i = index.get(frame.child_frame_id)
            if i is None:
                continue
            p, q = frame.translation, frame.rotation
            row[7 * i : 7 * i + 7] = (p.x, p.y, p.z, q.w, q.x, q.y, q.z)
        self.out.tf_times.append(t)
        self.out.poses.append(row)

    def _part(self, t: float, msg: Any, part: tuple[int, list[str]], is_bodies: bool) -> None:
        """One /bodies or /joints message: its names' values go into the step's row (a new row at a new
        time; the parts of one step share theirs)."""
        out = self.out
        times, rows = (out.motion_times, out.motions) if is_bodies else (out.joint_times, out.joint_rows)
        width = 6 if is_bodies else 3
        if not times or times[-1] != t:
            times.append(t)
            rows.append([math.nan] * (width * len(self.bodies if is_bodies else self.joints)))
        row, (first, names) = rows[-1], part
        values: list[float] = []
        for name in names:
            m = _member(msg, name)
            if m is None:
                values += [math.nan] * width
            elif is_bodies:
                v, w = m.vel, m.angvel
                values += (v.x, v.y, v.z, w.x, w.y, w.z)
            else:
                values += (m.position, m.velocity, m.motor_force)
        row[width * first : width * (first + len(names))] = values

    def _state(self, t: float, msg: Any) -> None:
        out = self.out
        n = len(out.state_times)
        out.state_times.append(t)
        for f in msg.DESCRIPTOR.fields:
            value = getattr(msg, f.name)
            if f.type not in (_FIELD_TYPE_BOOL, _FIELD_TYPE_STRING):
                value = float(value)
            out.state.setdefault(f.name, [None] * n).append(value)
        for values in out.state.values():
            values.extend([None] * (n + 1 - len(values)))

    def _sensors(self, t: float, msg: Any) -> None:
        out = self.out
        out.sensor_times.append(t)
        for f in msg.DESCRIPTOR.fields:
            out.sensors.setdefault(f.name, []).append(float(getattr(msg, f.name)))

    def _contacts(self, t: float, msg: Any) -> None:
        if msg.pairs:
            pairs = [{"a": p.a, "b": p.b, "points": p.points, "depth": p.depth, "normal_force": p.normal_force}
                     for p in msg.pairs]  # fmt: skip
            self.out.contacts.append((t, pairs))

    def _event(self, t: float, msg: Any) -> None:
        detail = {}
        for kv in msg.detail:
            try:
                detail[kv.key] = json.loads(kv.value)
            except json.JSONDecodeError:
                detail[kv.key] = kv.value
        self.out.events.append((t, msg.name, msg.source, detail))

    def _log(self, t: float, msg: Any) -> None:
        level = tf.LOG_LEVEL_NAMES.get(int(msg.level), "unknown")
        self.out.logs.append((t, level, msg.name, msg.message))

    def _sound(self, t: float, msg: Any) -> None:
        self.out.sounds.append((t, msg.name, msg.action, msg.offset, msg.volume))

    def _verdicts(self, t: float, msg: Any) -> None:
        for v in msg.verdicts:
            data: dict[str, Any] = {
                "name": v.name, "kind": v.kind, "passed": v.passed, "measured": v.measured,
                "expected": v.expected, "message": v.message,
            }  # fmt: skip
            for key in _VERDICT_NUMBERS:
                data[key] = getattr(v, key) if v.HasField(key) else None
            if v.HasField("known_limit"):  # an expected failure (the assertion's known_limits)
                data["known_limit"] = {"measured": v.known_limit.measured, "cause": v.known_limit.cause,
                                       "doc": v.known_limit.doc}  # fmt: skip
            self.out.verdicts.append((t, data))

    _handlers: dict[str, Callable[[MessageDecoder, float, Any], None]] = {
        tf.TOPIC_TF: _tf,
        tf.TOPIC_STATE: _state,
        tf.TOPIC_SENSORS: _sensors,
        tf.TOPIC_CONTACTS: _contacts,
        tf.TOPIC_EVENTS: _event,
        tf.TOPIC_LOG: _log,
        tf.TOPIC_SOUNDS: _sound,
        tf.TOPIC_VERDICTS: _verdicts,
    }


def body_arrays(decoded: Decoded, n_bodies: int) -> tuple[np.ndarray, np.ndarray]:
    """(times, (S, N, 13) rows in :data:`reports.trace_format.BODY_ROW` order) from /tf and /bodies, over the
    steps both hold (a recovered trace may end between the two)."""
    steps = min(len(decoded.tf_times), len(decoded.motion_times))
    poses = np.array(decoded.poses[:steps], dtype=float).reshape(steps, n_bodies, 7)
    motions = np.array(decoded.motions[:steps], dtype=float).reshape(steps, n_bodies, 6)
    return np.array(decoded.tf_times[:steps]), np.concatenate([poses, motions], axis=2)
