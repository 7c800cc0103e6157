"""The trace's encoding: what each channel's schema is and how each message becomes bytes.

:class:`TraceEncoder` is built once per trace from the scenario's names; the writer
(:mod:`runner.trace.writer`) registers :meth:`TraceEncoder.channels` and hands each call's encoded bytes
to MCAP. Per-step channels go through serialised templates (:mod:`runner.trace.slots`); the rest are
built message by message with google.protobuf.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from itertools import chain
from operator import is_
from typing import Any

import numpy as np

from reports import trace_format as tf
from runner.trace import foxglove as fx
from runner.trace import proto as pb
from runner.trace.proto.scenario import field_of, scenario_messages, sensors_class, with_state
from runner.trace.slots import PairTemplates, SlotTemplate, quantize

__all__ = ["Channel", "TraceEncoder", "dumps", "plain", "verdict_text"]


def _slices(parts: Sequence[Sequence[str]]) -> list[tuple[int, int]]:
    """Each part's rows: parts split the names in order."""
    ends = np.cumsum([0, *(len(p) for p in parts)]).tolist()
    return list(zip(ends[:-1], ends[1:], strict=True))


@dataclass(frozen=True)
class Channel:
    """A trace channel to register: its topic and its schema's name and bytes."""

    topic: str
    schema_name: str
    schema_data: bytes


def plain(value: Any) -> str:
    """A value as log text: numbers short, text as it is, anything else as JSON with its characters kept."""
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, float | int):
        return f"{value:.6g}"
    if isinstance(value, str):
        return value
    return json.dumps(value, ensure_ascii=False, separators=(", ", ": "), default=str)


def _json(value: Any) -> str:
    """JSON text for a detail value: non-finite floats as null, characters kept."""
    try:
        return json.dumps(value, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    except (TypeError, ValueError):
        return json.dumps(_finite(value), ensure_ascii=False, separators=(",", ":"), default=str)


def _finite(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def _optional(value: Any) -> float | None:
    """A verdict's optional number: present only when it is a finite number."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


class TraceEncoder:
    """Encoders for one trace's bodies and joints; its state variables join with :meth:`state_channel`."""

    def __init__(self, bodies: Sequence[str], joints: Sequence[str]) -> None:
        self.bodies = list(bodies)
        self.joints = list(joints)
        self.messages = scenario_messages(self.bodies, self.joints)
        width, jwidth = len(tf.BODY_ROW), len(tf.JOINT_FIELDS)
        self._rows = np.empty((len(self.bodies), width))
        self._tf = fx.transforms_template(self.bodies)
        body_parts, joint_parts = self.messages.body_parts, self.messages.joint_parts
        #: /bodies, then /bodies/2 ... for a world of more than 8,000 bodies; likewise /joints
        self.body_topics = [tf.part_topic(tf.TOPIC_BODIES, k) for k in range(len(body_parts))]
        self.joint_topics = [tf.part_topic(tf.TOPIC_JOINTS, k) for k in range(len(joint_parts))] if self.joints else []
        self._body_slices = _slices(body_parts)
        self._joint_slices = _slices(joint_parts)
        self._bodies = [SlotTemplate(self._filler(cls, part, self._fill_bodies), width * len(part))
                        for cls, part in zip(self.messages.bodies, body_parts, strict=True)]  # fmt: skip
        self._joints = [SlotTemplate(self._filler(cls, part, self._fill_joints), jwidth * len(part))
                        for cls, part in zip(self.messages.joints, joint_parts, strict=True)]  # fmt: skip
        self._jrows = np.empty((len(self.joints), jwidth))
        #: the last /state message: its variables' names, their value objects, its bytes (``state_message``)
        self._last_state: tuple[tuple[str, ...], tuple[Any, ...], bytes] = ((), (), b"")
        self._pairs = PairTemplates(len(self.bodies), self._contacts_head, self._contact_pair)

    # ---- schemas ----------------------------------------------------------------------------------
    def channels(self) -> list[Channel]:
        """The trace's channels but /state, in registration order (/joints only when there are joints)."""
        m = self.messages
        out = [
            (tf.TOPIC_TF, fx.FrameTransforms),
            (tf.TOPIC_SCENE, fx.SceneUpdate),
            (tf.TOPIC_SCENE_COLLISION, fx.SceneUpdate),  # written only when a body has visuals
            (tf.TOPIC_LOG, fx.Log),
            *zip(self.body_topics, m.bodies, strict=True),
            *zip(self.joint_topics, m.joints, strict=False),  # none when there are no joints
            (tf.TOPIC_CONTACTS, pb.Contacts),
            (tf.TOPIC_EVENTS, pb.Event),
            (tf.TOPIC_SOUNDS, pb.Sound),
            (tf.TOPIC_AUDIO, fx.RawAudio),
            (tf.TOPIC_VERDICTS, pb.Verdicts),
        ]
        return [Channel(topic, cls.DESCRIPTOR.full_name, pb.schema_data(cls)) for topic, cls in out if cls is not None]

    def state_channel(self, initial: Mapping[str, Any]) -> Channel:
        """/state, typed by the variables' first values (the writer registers it at the first step)."""
        self.messages = with_state(self.messages, initial)
        cls = self.messages.state
        return Channel(tf.TOPIC_STATE, cls.DESCRIPTOR.full_name, pb.schema_data(cls))

    def sensors_channel(self, names: Sequence[str]) -> Channel:
        """/sensors for the sensor quantities ``names`` (the writer registers it at the first step)."""
        self._sensor_fields = [tf.sensor_field(n) for n in names]
        self._sensors = sensors_class(self._sensor_fields)
        return Channel(tf.TOPIC_SENSORS, self._sensors.DESCRIPTOR.full_name, pb.schema_data(self._sensors))

    def sensors_message(self, values: Sequence[float]) -> bytes:
        """/sensors: the values in the channel's order, rounded to 1e-9 as every per-step double."""
        msg = self._sensors()
        for name, value in zip(self._sensor_fields, quantize(np.asarray(values, float)).tolist(), strict=True):
            setattr(msg, name, value)
        return bytes(msg.SerializeToString(deterministic=True))

    # ---- per step ---------------------------------------------------------------------------------
    @staticmethod
    def _filler(cls: Any, names: Sequence[str], fill: Callable[[Any, Sequence[str], np.ndarray], Any]) -> Any:
        return lambda values: fill(cls(), names, values)

    @staticmethod
    def _fill_bodies(msg: Any, names: Sequence[str], values: np.ndarray) -> Any:
        vx = tf.BODY_ROW.index("vel.x")
        for name, row in zip(names, values.reshape(-1, len(tf.BODY_ROW)).tolist(), strict=True):
            b = field_of(msg, name)
            b.vel.x, b.vel.y, b.vel.z = row[vx : vx + 3]
            b.angvel.x, b.angvel.y, b.angvel.z = row[vx + 3 : vx + 6]
        return msg

    @staticmethod
    def _fill_joints(msg: Any, names: Sequence[str], values: np.ndarray) -> Any:
        for name, row in zip(names, values.reshape(-1, len(tf.JOINT_FIELDS)).tolist(), strict=True):
            j = field_of(msg, name)
            j.position, j.velocity, j.motor_force = row
        return msg

    @staticmethod
    def _contacts_head(count: int) -> Any:
        return pb.Contacts(count=count)

    def _contact_pair(self, a: int, b: int, points: int, depth: float, force: float) -> Any:
        pair = pb.ContactPair(a=self.bodies[a], b=self.bodies[b], points=points, depth=depth, normal_force=force)
        return pb.Contacts(pairs=[pair])

    def transforms_and_bodies(self, ns: int, rows: np.ndarray) -> tuple[bytes, list[bytes]]:
        """/tf and the /bodies messages (one per :attr:`body_topics`) for the step's (N, 13) body rows
        (``BodyStates.rows()``)."""
        q = self._rows
        np.multiply(rows, 1e9, out=q)  # quantize() in place: one buffer per trace
        np.rint(q, out=q)
        np.divide(q, 1e9, out=q)
        parts = zip(self._bodies, self._body_slices, strict=True)
        return self._tf.render(q, ns), [t.render(q[a:b]) for t, (a, b) in parts]

    def joints_messages(self, position: np.ndarray, velocity: np.ndarray, motor_force: np.ndarray) -> list[bytes]:
        """The /joints messages, one per :attr:`joint_topics`."""
        j = self._jrows
        j[:, 0], j[:, 1], j[:, 2] = position, velocity, motor_force
        q = quantize(j)
        return [t.render(q[a:b]) for t, (a, b) in zip(self._joints, self._joint_slices, strict=True)]

    def contacts_message(self, contacts: Sequence[tuple[int, int, int, float, float]]) -> bytes:
        """/contacts from the backends' ``Contact`` rows (a, b, points, depth, normal_force)."""
        if not contacts:
            return b""  # Contacts(count=0): every field at its default
        pairs = np.fromiter(chain.from_iterable(contacts), dtype=np.float64, count=5 * len(contacts)).reshape(-1, 5)
        pairs[:, 3:] = quantize(pairs[:, 3:])
        return self._pairs.render(pairs)

    def state_message(self, values: Mapping[str, Any]) -> bytes:
        """/state; a value whose type differs from its variable's declared one is converted to it. The state
        changes only when a handler sets it: a step whose values are the very objects of the last message's
        (immutable: bools, numbers, text; held here, so none is another's) reuses its bytes."""
        names, objects = tuple(values), tuple(values.values())
        last_names, last_objects, last_data = self._last_state
        if names == last_names and all(map(is_, objects, last_objects)):
            return last_data
        data = self._state_bytes(values)
        self._last_state = (names, objects, data)
        return data

    def _state_bytes(self, values: Mapping[str, Any]) -> bytes:
        msg = self.messages.state()
        for name, kind in self.messages.state_types.items():
            if name not in values:
                continue
            v = values[name]
            if kind == "bool":
                setattr(msg, name, bool(v) if not isinstance(v, str) else v.strip().lower() in ("true", "1"))
            elif kind == "double":
                setattr(msg, name, float(v) if isinstance(v, bool | int | float) else math.nan)
            else:
                setattr(msg, name, v if isinstance(v, str) else plain(v))
        return bytes(msg.SerializeToString(deterministic=True))

    # ---- occasional messages ------------------------------------------------------------------------
    @staticmethod
    def event(t: float, name: str, source: str, detail: Mapping[str, Any] | None) -> bytes:
        items = [pb.KeyValue(key=str(k), value=_json(v)) for k, v in (detail or {}).items()]
        return bytes(pb.Event(time=t, name=name, source=source, detail=items).SerializeToString(deterministic=True))

    @staticmethod
    def sound(t: float, name: str, action: str, offset: float, volume: float) -> bytes:
        msg = pb.Sound(time=t, name=name, action=action, offset=offset, volume=volume)
        return bytes(msg.SerializeToString(deterministic=True))

    @staticmethod
    def verdicts(t: float, verdicts: Sequence[Mapping[str, Any]]) -> bytes:
        msg = pb.Verdicts(time=t)
        for v in verdicts:
            item = msg.verdicts.add(
                name=str(v.get(tf.VERDICT_NAME, "")), kind=str(v.get("kind", "")),
                passed=v.get(tf.VERDICT_PASSED) is True, measured=str(v.get(tf.VERDICT_MEASURED, "")),
                expected=str(v.get(tf.VERDICT_EXPECTED, "")), message=str(v.get("message", "") or ""),
            )  # fmt: skip
            for key in ("time", "value", "target", "tolerance"):
                number = _optional(v.get(key))
                if number is not None:
                    setattr(item, key, number)
            limit = v.get("known_limit")
            if isinstance(limit, Mapping):  # an expected failure; absent otherwise (the bytes stay as they were)
                item.known_limit.measured = float(limit.get("measured", 0.0))
                item.known_limit.cause, item.known_limit.doc = str(limit.get("cause", "")), str(limit.get("doc", ""))
        return bytes(msg.SerializeToString(deterministic=True))

    @staticmethod
    def log(ns: int, level: int, message: str, name: str) -> bytes:
        return bytes(fx.log(ns, level, message, name).SerializeToString(deterministic=True))

    @staticmethod
    def scene(entities: Sequence[Any]) -> bytes:
        return bytes(fx.SceneUpdate(entities=list(entities)).SerializeToString(deterministic=True))

    @staticmethod
    def audio(ns: int, pcm: np.ndarray, sample_rate: int) -> bytes:
        return bytes(fx.raw_audio(ns, pcm, sample_rate).SerializeToString(deterministic=True))


def verdict_text(v: Mapping[str, Any]) -> tuple[str, str]:
    """(level, log text) of one verdict: ``PASS kick: measured 2.57 (expected 2.57 ± 0.001)``."""
    passed = v.get(tf.VERDICT_PASSED)
    limit = passed is True and isinstance(v.get("known_limit"), Mapping)  # an expected failure
    level = "warning" if limit else "info" if passed is True else "error" if passed is False else "warning"
    label = "KNOWN LIMIT" if limit else "PASS" if passed is True else "FAIL" if passed is False else "????"
    text = f"{label} {v.get(tf.VERDICT_NAME, '?')}"
    if tf.VERDICT_MEASURED in v:
        text += f": measured {plain(v[tf.VERDICT_MEASURED])}"
    if tf.VERDICT_EXPECTED in v:
        text += f" (expected {plain(v[tf.VERDICT_EXPECTED])})"
    if v.get("message"):
        text += f"; {plain(v['message'])}"
    return level, text


def dumps(obj: Any, sort_keys: bool = False, ensure_ascii: bool = True) -> str:
    """Compact JSON for metadata values: NaN and infinities as null, numpy values as Python ones, anything
    else as str()."""
    try:  # the common case, entirely in the C encoder
        return json.dumps(obj, separators=(",", ":"), allow_nan=False, sort_keys=sort_keys, ensure_ascii=ensure_ascii)
    except (TypeError, ValueError):
        return json.dumps(_plain_json(obj), separators=(",", ":"), allow_nan=False, default=str, sort_keys=sort_keys,
                          ensure_ascii=ensure_ascii)  # fmt: skip


def _plain_json(obj: Any) -> Any:
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, float | np.floating):
        x = float(obj)
        return x if math.isfinite(x) else None
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, Mapping):
        return {str(k): _plain_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple | np.ndarray):
        return [_plain_json(v) for v in obj]
    return obj
