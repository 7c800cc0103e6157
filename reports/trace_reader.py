"""Reading a trace back: metadata, channels, per-step arrays, events, logs, sounds, verdicts.

The file is read front to back with mcap's non-seeking stream reader, which needs no summary section,
so the same code reads a finished trace and, with ``recover=True``, one cut off by a hard kill: it
stops cleanly at the first record that is incomplete or fails its CRC, keeping everything before it
(all complete chunks). Without ``recover`` a damaged or unfinished file raises :class:`TraceReadError`.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, cast

import numpy as np
from mcap.exceptions import InvalidMagic, McapError
from mcap.records import Attachment, Channel, Footer, Message, Metadata, Schema
from mcap.stream_reader import StreamReader

from reports import trace_format as tf

__all__ = [
    "AttachmentInfo",
    "BodySeries",
    "ChannelInfo",
    "EventRecord",
    "JointSeries",
    "LogRecord",
    "SoundRecord",
    "Trace",
    "TraceReadError",
    "Verdict",
    "read_trace",
]


class TraceReadError(Exception):
    """A trace cannot be read (missing, not MCAP, damaged, or unfinished without ``recover``)."""


class _Truncated(Exception):
    """Raised by the strict stream where the file ends inside a record."""


class _StrictStream:
    """A file whose ``read(n)`` returns exactly n bytes or raises: a cut-off record never parses."""

    def __init__(self, f: IO[bytes]) -> None:
        self._f = f
        self.offset = 0

    def read(self, n: int) -> bytes:
        data = self._f.read(n)
        self.offset += len(data)
        if len(data) < n:
            raise _Truncated(f"the file ends at byte {self.offset}, inside a record")
        return data


@dataclass
class ChannelInfo:
    topic: str
    schema: str
    schema_encoding: str
    message_encoding: str
    count: int = 0


@dataclass
class BodySeries:
    """One body's state at each time of :attr:`Trace.times`; quaternions (w, x, y, z)."""

    pos: np.ndarray  # (S, 3)
    quat: np.ndarray  # (S, 4)
    vel: np.ndarray  # (S, 3)
    angvel: np.ndarray  # (S, 3)


@dataclass
class JointSeries:
    """One joint's state at each time of :attr:`Trace.joint_times` (NaN where it has none)."""

    position: np.ndarray
    velocity: np.ndarray
    motor_force: np.ndarray


@dataclass
class EventRecord:
    t: float
    name: str
    source: str
    detail: dict[str, Any] = field(default_factory=dict)


@dataclass
class LogRecord:
    t: float
    level: str
    name: str
    message: str


@dataclass
class SoundRecord:
    t: float
    name: str
    action: str
    offset: float
    volume: float


@dataclass
class Verdict:
    t: float
    data: dict[str, Any]

    @property
    def name(self) -> str:
        return str(self.data.get(tf.VERDICT_NAME, "?"))

    @property
    def passed(self) -> bool | None:
        value = self.data.get(tf.VERDICT_PASSED)
        return value if isinstance(value, bool) else None


@dataclass
class AttachmentInfo:
    name: str
    media_type: str
    size: int
    data: bytes = field(repr=False, default=b"")


@dataclass
class Trace:
    path: Path
    complete: bool  # the file ends with its footer
    recovered: bool  # reading stopped at a damaged or cut-off record (recover=True)
    metadata: dict[str, dict[str, str]]
    channels: dict[str, ChannelInfo]
    start_time: float | None  # seconds, over all messages
    end_time: float | None
    times: np.ndarray  # /bodies times
    bodies: dict[str, BodySeries]
    joint_times: np.ndarray
    joints: dict[str, JointSeries]
    state_times: np.ndarray
    state: dict[str, list[Any]]
    contacts: list[tuple[float, list[dict[str, Any]]]]  # steps with at least one touching pair
    events: list[EventRecord]
    logs: list[LogRecord]
    sounds: list[SoundRecord]
    verdicts: list[Verdict]
    attachments: list[AttachmentInfo]
    stop_reason: str = ""  # why reading stopped early (recover=True)

    @property
    def scenario(self) -> dict[str, str]:
        return self.metadata.get(tf.METADATA_SCENARIO, {})

    @property
    def result(self) -> dict[str, str]:
        return self.metadata.get(tf.METADATA_RESULT, {})

    @property
    def status(self) -> str:
        return self.result.get(tf.KEY_STATUS, tf.STATUS_INCOMPLETE)

    @property
    def summary(self) -> dict[str, Any]:
        text = self.result.get(tf.KEY_SUMMARY)
        return json.loads(text) if text else {}

    @property
    def duration(self) -> float:
        """Simulated time covered by the recorded steps."""
        return float(self.times[-1] - self.times[0]) if self.times.size else 0.0

    def series(self, path: str) -> tuple[np.ndarray, np.ndarray]:
        """(times, values) of ``box.pos.z``, ``box.quat.w``, ``slider.position`` or ``state.name``."""
        parts = path.split(".")
        if parts[0] == "state" and len(parts) == 2 and parts[1] in self.state:
            values = [np.nan if v is None else v for v in self.state[parts[1]]]
            return self.state_times, np.asarray(values)
        if parts[0] in self.bodies and len(parts) == 3 and parts[1] in tf.BODY_FIELDS:
            keys = tf.QUAT_KEYS if parts[1] == "quat" else tf.VEC_KEYS
            if parts[2] in keys:
                arr = getattr(self.bodies[parts[0]], parts[1])
                return self.times, arr[:, keys.index(parts[2])]
        if parts[0] in self.joints and len(parts) == 2 and parts[1] in tf.JOINT_FIELDS:
            return self.joint_times, getattr(self.joints[parts[0]], parts[1])
        raise KeyError(f"no series {path!r} in {self.path}")

    def attachment(self, name: str) -> bytes:
        for a in self.attachments:
            if a.name == name:
                return a.data
        raise KeyError(f"no attachment {name!r} in {self.path}")


_BROKEN = (_Truncated, McapError, struct.error, ValueError, RuntimeError, EOFError, UnicodeDecodeError)


def _records(stream: _StrictStream, recover: bool, path: Path) -> Iterator[Any]:
    records = iter(StreamReader(cast(IO[bytes], stream), validate_crcs=True).records)
    started = False
    while True:
        try:
            record = next(records)
        except StopIteration:
            return
        except InvalidMagic as exc:
            if not started:
                raise TraceReadError(f"{path} is not an MCAP file") from exc
            raise TraceReadError(f"{path} does not end like an MCAP file ({exc})") from exc
        except _BROKEN as exc:
            if not recover:
                raise TraceReadError(
                    f"{path} is damaged or unfinished ({exc}); read what it holds with recover=True "
                    "(`scenario inspect --recover`)"
                ) from exc
            yield exc
            return
        started = True
        yield record


class _Builder:
    """Accumulates decoded messages; arrays are built once at the end."""

    def __init__(self) -> None:
        self.times: list[float] = []
        self.body_names: list[str] = []
        self.body_rows: list[list[Any]] = []
        self.joint_times: list[float] = []
        self.joint_names: list[str] = []
        self.joint_rows: list[list[Any]] = []
        self.state_times: list[float] = []
        self.state: dict[str, list[Any]] = {}
        self.contacts: list[tuple[float, list[dict[str, Any]]]] = []
        self.events: list[EventRecord] = []
        self.logs: list[LogRecord] = []
        self.sounds: list[SoundRecord] = []
        self.verdicts: list[Verdict] = []

    def add(self, topic: str, t: float, data: bytes) -> None:
        if topic in (tf.TOPIC_TF, tf.TOPIC_SCENE):
            return  # /bodies carries the same poses; the scene is for Foxglove
        msg = json.loads(data)
        if topic == tf.TOPIC_BODIES:
            if not self.body_names:
                self.body_names = list(msg)
            self.times.append(t)
            row: list[Any] = []
            for name in self.body_names:
                b = msg[name]
                p, q, v, w = b["pos"], b["quat"], b["vel"], b["angvel"]
                row += (p["x"], p["y"], p["z"], q["w"], q["x"], q["y"], q["z"])
                row += (v["x"], v["y"], v["z"], w["x"], w["y"], w["z"])
            self.body_rows.append(row)
        elif topic == tf.TOPIC_JOINTS:
            if not self.joint_names:
                self.joint_names = list(msg)
            self.joint_times.append(t)
            self.joint_rows.append([msg[j][k] for j in self.joint_names for k in tf.JOINT_FIELDS])
        elif topic == tf.TOPIC_STATE:
            n = len(self.state_times)
            self.state_times.append(t)
            for k, v in msg.items():
                self.state.setdefault(k, [None] * n).append(v)
            for values in self.state.values():
                values.extend([None] * (n + 1 - len(values)))
        elif topic == tf.TOPIC_CONTACTS:
            if msg.get("pairs"):
                self.contacts.append((t, msg["pairs"]))
        elif topic == tf.TOPIC_EVENTS:
            self.events.append(EventRecord(t, msg["name"], msg["source"], msg.get("detail") or {}))
        elif topic == tf.TOPIC_LOG:
            level = tf.LOG_LEVEL_NAMES.get(msg.get("level", 0), "unknown")
            self.logs.append(LogRecord(t, level, msg.get("name", ""), msg.get("message", "")))
        elif topic == tf.TOPIC_SOUNDS:
            self.sounds.append(SoundRecord(t, msg["name"], msg["action"], msg["offset"], msg["volume"]))
        elif topic == tf.TOPIC_VERDICTS:
            self.verdicts += [Verdict(t, v) for v in msg.get("verdicts", [])]

    def bodies(self) -> dict[str, BodySeries]:
        arr = np.array(self.body_rows, dtype=float).reshape(len(self.times), len(self.body_names), 13)
        return {
            name: BodySeries(arr[:, i, 0:3], arr[:, i, 3:7], arr[:, i, 7:10], arr[:, i, 10:13])
            for i, name in enumerate(self.body_names)
        }

    def joints(self) -> dict[str, JointSeries]:
        arr = np.array(self.joint_rows, dtype=float).reshape(len(self.joint_times), len(self.joint_names), 3)
        return {name: JointSeries(arr[:, i, 0], arr[:, i, 1], arr[:, i, 2]) for i, name in enumerate(self.joint_names)}


def read_trace(path: str | Path, recover: bool = False) -> Trace:
    """Read a trace; ``recover=True`` also reads an unfinished (``.partial``) or cut-off one."""
    path = Path(path)
    if not path.exists():
        partial = path.with_name(path.name + tf.PARTIAL_SUFFIX)
        if recover and partial.exists():
            path = partial
        else:
            hint = f"; an unfinished trace exists at {partial} (read it with recover=True)" if partial.exists() else ""
            raise TraceReadError(f"{path} does not exist{hint}")
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    metadata: dict[str, dict[str, str]] = {}
    attachments: list[AttachmentInfo] = []
    build = _Builder()
    counts: dict[int, int] = {}
    first: int | None = None
    last: int | None = None
    complete, stop_reason = False, ""
    try:
        with open(path, "rb") as f:
            for record in _records(_StrictStream(f), recover, path):
                if isinstance(record, Exception):
                    if not metadata and not channels:
                        raise TraceReadError(f"{path} holds no readable trace: {record}") from record
                    stop_reason = str(record) or type(record).__name__
                elif isinstance(record, Message):
                    ch = channels[record.channel_id]
                    counts[ch.id] = counts.get(ch.id, 0) + 1
                    first = record.log_time if first is None else min(first, record.log_time)
                    last = record.log_time if last is None else max(last, record.log_time)
                    build.add(ch.topic, record.log_time / 1e9, record.data)
                elif isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Metadata):
                    metadata[record.name] = dict(record.metadata)
                elif isinstance(record, Attachment):
                    attachments.append(AttachmentInfo(record.name, record.media_type, len(record.data), record.data))
                elif isinstance(record, Footer):
                    complete = True
    except OSError as exc:
        raise TraceReadError(f"cannot read {path}: {exc.strerror or exc}") from exc
    except (KeyError, TypeError, json.JSONDecodeError) as exc:
        raise TraceReadError(f"{path} is not a physics-scenarios trace: {type(exc).__name__}: {exc}") from exc
    if not complete and not recover:
        raise TraceReadError(f"{path} has no footer (unfinished); read what it holds with recover=True")
    infos: dict[str, ChannelInfo] = {}
    for ch in channels.values():
        schema = schemas.get(ch.schema_id)
        infos[ch.topic] = ChannelInfo(
            ch.topic, schema.name if schema else "", schema.encoding if schema else "", ch.message_encoding,
            counts.get(ch.id, 0),
        )  # fmt: skip
    return Trace(
        path=path,
        complete=complete,
        recovered=bool(stop_reason),
        metadata=metadata,
        channels=infos,
        start_time=None if first is None else first / 1e9,
        end_time=None if last is None else last / 1e9,
        times=np.array(build.times),
        bodies=build.bodies(),
        joint_times=np.array(build.joint_times),
        joints=build.joints(),
        state_times=np.array(build.state_times),
        state=build.state,
        contacts=build.contacts,
        events=build.events,
        logs=build.logs,
        sounds=build.sounds,
        verdicts=build.verdicts,
        attachments=attachments,
        stop_reason=stop_reason,
    )
