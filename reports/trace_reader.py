"""Reading a trace back: metadata, channels, per-step arrays, events, logs, sounds, verdicts.

The file is read front to back with mcap's non-seeking stream reader, which needs no summary section,
so the same code reads a finished trace and, with ``recover=True``, one cut off by a hard kill: it
stops cleanly at the first record that is incomplete or fails its CRC, keeping everything before it
(all complete chunks). Without ``recover`` a damaged or unfinished file raises :class:`TraceReadError`.
Messages are decoded by :mod:`reports.trace_decode` (format 2, protobuf); a trace of another format
version is refused with a message naming it.
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
from reports.trace_decode import MessageDecoder, UnreadableMessage, body_arrays

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

    @property
    def status(self) -> str | None:
        """passed, failed, ``known limit`` (an expected failure: passed, with its ``known_limit``), or None."""
        passed = self.passed
        if passed is None:
            return None
        return "known limit" if passed and self.data.get("known_limit") else "passed" if passed else "failed"


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
        if len(parts) > 2 and (f"{parts[0]}.{parts[1]}" in self.bodies or f"{parts[0]}.{parts[1]}" in self.joints):
            parts = [f"{parts[0]}.{parts[1]}", *parts[2:]]  # a robot's link or joint: `arm.link_7.pos.z`
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


def _check_format(path: Path, metadata: dict[str, str]) -> None:
    version = metadata.get(tf.KEY_TRACE_FORMAT, "")
    if version == str(tf.TRACE_FORMAT_VERSION):
        return
    known = tf.PREVIOUS_FORMATS.get(int(version)) if version.isdigit() else None
    what = f"trace format {version or '(none)'}" + (f" ({known})" if known else "")
    raise TraceReadError(
        f"{path} is in {what}; this version of physics-scenarios reads trace format {tf.TRACE_FORMAT_VERSION} "
        "only. Run the scenario again to get a trace in the current format."
    )


def _names(metadata: dict[str, str], key: str) -> list[str]:
    try:
        names = json.loads(metadata.get(key, "[]"))
    except json.JSONDecodeError as exc:
        raise TraceReadError(f"the scenario record's {key!r} is not a JSON list: {exc}") from exc
    return [str(n) for n in names]


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
    decoder: MessageDecoder | None = None
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
                    if decoder is None:
                        scenario = metadata.get(tf.METADATA_SCENARIO)
                        if scenario is None:
                            raise TraceReadError(f"{path} has messages before its scenario record: not a "
                                                 "physics-scenarios trace")  # fmt: skip
                        decoder = MessageDecoder(_names(scenario, tf.KEY_BODIES), _names(scenario, tf.KEY_JOINTS))
                    decoder.add(ch.topic, schemas.get(ch.schema_id), ch.message_encoding, record.log_time / 1e9,
                                record.data)  # fmt: skip
                elif isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Metadata):
                    metadata[record.name] = dict(record.metadata)
                    if record.name == tf.METADATA_SCENARIO:
                        _check_format(path, metadata[record.name])
                elif isinstance(record, Attachment):
                    attachments.append(AttachmentInfo(record.name, record.media_type, len(record.data), record.data))
                elif isinstance(record, Footer):
                    complete = True
    except OSError as exc:
        raise TraceReadError(f"cannot read {path}: {exc.strerror or exc}") from exc
    except (KeyError, TypeError, UnreadableMessage) as exc:
        raise TraceReadError(f"{path} is not a physics-scenarios trace: {type(exc).__name__}: {exc}") from exc
    if not complete and not recover:
        raise TraceReadError(f"{path} has no footer (unfinished); read what it holds with recover=True")
    if tf.METADATA_SCENARIO not in metadata and any(s.encoding == "jsonschema" for s in schemas.values()):
        _check_format(path, {})
    infos: dict[str, ChannelInfo] = {}
    for ch in channels.values():
        schema = schemas.get(ch.schema_id)
        infos[ch.topic] = ChannelInfo(
            ch.topic, schema.name if schema else "", schema.encoding if schema else "", ch.message_encoding,
            counts.get(ch.id, 0),
        )  # fmt: skip
    decoded = decoder.out if decoder is not None else MessageDecoder([], []).out
    bodies = decoder.bodies if decoder is not None else []
    joints = decoder.joints if decoder is not None else []
    times, rows = body_arrays(decoded, len(bodies))
    jrows = np.array(decoded.joint_rows, dtype=float).reshape(len(decoded.joint_times), len(joints), 3)
    return Trace(
        path=path,
        complete=complete,
        recovered=bool(stop_reason),
        metadata=metadata,
        channels=infos,
        start_time=None if first is None else first / 1e9,
        end_time=None if last is None else last / 1e9,
        times=times,
        bodies={
            name: BodySeries(rows[:, i, 0:3], rows[:, i, 3:7], rows[:, i, 7:10], rows[:, i, 10:13])
            for i, name in enumerate(bodies)
        },  # fmt: skip
        joint_times=np.array(decoded.joint_times),
        joints={name: JointSeries(jrows[:, i, 0], jrows[:, i, 1], jrows[:, i, 2]) for i, name in enumerate(joints)},
        state_times=np.array(decoded.state_times),
        state=decoded.state,
        contacts=decoded.contacts,
        events=[EventRecord(*e) for e in decoded.events],
        logs=[LogRecord(*entry) for entry in decoded.logs],
        sounds=[SoundRecord(*entry) for entry in decoded.sounds],
        verdicts=[Verdict(t, data) for t, data in decoded.verdicts],
        attachments=attachments,
        stop_reason=stop_reason,
    )
