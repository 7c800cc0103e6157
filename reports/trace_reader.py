"""Reading a trace back: metadata, channels, per-step arrays, events, logs, sounds, verdicts.

The file is read front to back, record by record (mcap's record parsers, no summary section needed), so
the same code reads a finished trace and, with ``recover=True``, one cut off by a hard kill or damaged:
a record whose bytes are whole but unreadable (a flipped bit in a chunk) is skipped and reading goes on
after it; a record cut off ends the reading, keeping everything before it. Without ``recover`` a damaged
or unfinished file raises :class:`TraceReadError` ("damaged at byte N"). Anything else that goes wrong
(garbage schemas, JSON, names) is "not a physics-scenarios trace". Messages are decoded by
:mod:`reports.trace_decode` (format 2, protobuf); a trace of another format version is refused with a
message naming it.
"""

from __future__ import annotations

import io
import json
import os
import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np
from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Attachment, Channel, Chunk, Footer, Header, Message, Metadata, Schema

from reports import trace_format as tf
from reports.trace_chunks import check_schema, chunk_records
from reports.trace_decode import MessageDecoder, body_arrays

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
    sensor_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: /sensors: each sensor quantity the scenario read (``box.kinetic_energy``, ``shoulder.reaction.torque.y``)
    sensors: dict[str, np.ndarray] = field(default_factory=dict)

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
        return _json(text) if text else {}  # checked when the trace was read

    @property
    def duration(self) -> float:
        """Simulated time covered by the recorded steps."""
        return float(self.times[-1] - self.times[0]) if self.times.size else 0.0

    def series(self, path: str) -> tuple[np.ndarray, np.ndarray]:
        """(times, values) of ``box.pos.z``, ``box.quat.w``, ``slider.position`` or ``state.name``."""
        parts = path.split(".")
        for k in range(len(parts) - 1, 1, -1):  # a robot's link or joint, its name possibly dotted: `arm.a.b.pos.z`
            owner = ".".join(parts[:k])
            if owner in self.bodies or owner in self.joints:
                parts = [owner, *parts[k:]]
                break
        if path in self.sensors:
            return self.sensor_times, self.sensors[path]
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


#: Bounds checked before the work: a chunk's uncompressed size (the writer closes chunks at 1 MiB; one
#: 130 KB zstd chunk declaring 2 GB was inflated whole), and the bodies and joints a trace names (each is a
#: column of every step: 300,000 names in a 3.2 MB trace took 13.5 GB).
MAX_CHUNK_BYTES = 256 * 1024 * 1024
MAX_TRACE_NAMES = 100_000

_MAGIC = b"\x89MCAP0\r\n"
_READERS: dict[int, Callable[[ReadDataStream, int], Any]] = {
    Opcode.HEADER: lambda s, n: Header.read(s),
    Opcode.FOOTER: lambda s, n: Footer.read(s),
    Opcode.SCHEMA: lambda s, n: Schema.read(s),
    Opcode.CHANNEL: lambda s, n: Channel.read(s),
    Opcode.MESSAGE: Message.read,
    Opcode.CHUNK: lambda s, n: Chunk.read(s),
    Opcode.ATTACHMENT: lambda s, n: Attachment.read(s),
    Opcode.METADATA: lambda s, n: Metadata.read(s),
}  # the other records (indexes, statistics) hold nothing the reader needs


class Damage(Exception):
    """A record that cannot be read, at its byte offset: skipped when recovering, else the trace is refused."""

    def __init__(self, offset: int, what: str) -> None:
        super().__init__(f"damaged at byte {offset}: {what}")
        self.offset = offset


def _record(opcode: int, body: bytes) -> list[Any]:
    """The records of one record's bytes (a chunk's, decompressed and checked); raises on damage."""
    read = _READERS.get(opcode)
    if read is None:
        return []
    if opcode == Opcode.ATTACHMENT and len(body) >= 4:
        crc = struct.unpack_from("<I", body, len(body) - 4)[0]
        if crc and crc != zlib.crc32(body[:-4]):
            raise ValueError("the attachment fails its CRC")
    if opcode == Opcode.CHUNK:
        size = struct.unpack_from("<Q", body, 16)[0] if len(body) >= 24 else 0
        if size > MAX_CHUNK_BYTES:
            raise ValueError(f"a chunk declares {size} bytes uncompressed (at most {MAX_CHUNK_BYTES} are read)")
    record = read(ReadDataStream(io.BytesIO(body)), len(body))
    if isinstance(record, Chunk):
        return chunk_records(record)
    return [record]


def _records(f: IO[bytes], size: int, recover: bool, path: Path) -> Iterator[Any]:
    """The records, front to back; a damaged one is yielded as a :class:`Damage`. A record whose bytes are
    whole but unreadable (a flipped bit in a chunk: its CRC or its compression fails) is skipped and
    reading goes on after it; a record cut off, or claiming more bytes than the file holds, ends the
    reading (nothing after it can be framed). Without ``recover`` the first damage raises."""
    if f.read(len(_MAGIC)) != _MAGIC:
        raise TraceReadError(f"{path} is not a physics-scenarios trace (not an MCAP file)")
    offset = len(_MAGIC)
    while True:
        head = f.read(9)
        if not head:  # the end of the file without its footer: unfinished (the caller refuses it unless recover)
            if recover:
                yield Damage(offset, "the file ends here, before its footer (unfinished)")
            return
        damage: Damage | None = None
        if len(head) < 9:
            damage = Damage(offset, "the file ends inside a record")
        else:
            opcode, length = struct.unpack("<BQ", head)
            if length > size - offset - 9:
                damage = Damage(offset, f"a record of {length} bytes; the file holds {size - offset - 9} more")
        if damage is None:
            body = f.read(length)
            try:
                records = _record(opcode, body)
            except Exception as exc:  # noqa: BLE001 - whatever a damaged record raises (zstd, CRC, struct...)
                found = Damage(offset, str(exc)[:300] or type(exc).__name__)
                if not recover:
                    raise TraceReadError(f"{path} is {found}; read what it holds with recover=True "
                                         "(`scenario inspect --recover`)") from exc  # fmt: skip
                yield found
                offset += 9 + length
                continue
            yield from records
            if opcode == Opcode.FOOTER:
                return
            offset += 9 + length
            continue
        if not recover:
            raise TraceReadError(f"{path} is {damage} (unfinished?); read what it holds with recover=True "
                                 "(`scenario inspect --recover`)")  # fmt: skip
        yield damage
        return


def _check_format(path: Path, metadata: dict[str, str]) -> None:
    version = metadata.get(tf.KEY_TRACE_FORMAT, "")
    if version == str(tf.TRACE_FORMAT_VERSION):
        return
    known = tf.PREVIOUS_FORMATS.get(int(version)) if version.isascii() and version.isdigit() else None
    what = f"trace format {version or '(none)'}" + (f" ({known})" if known else "")
    raise TraceReadError(
        f"{path} is in {what}; this version of physics-scenarios reads trace format {tf.TRACE_FORMAT_VERSION} "
        "only. Run the scenario again to get a trace in the current format."
    )


def _json(text: str) -> Any:
    """JSON from a trace; nesting too deep to parse is refused like malformed text."""
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError("JSON nested too deeply") from None


def _names(path: Path, metadata: dict[str, str], key: str) -> list[str]:
    try:
        names = _json(metadata.get(key, "[]"))
    except ValueError as exc:
        raise TraceReadError(f"{path}: the scenario record's {key!r} is not a JSON list: {exc}") from exc
    if not isinstance(names, list):
        raise TraceReadError(f"{path}: the scenario record's {key!r} is not a JSON list")
    if len(names) > MAX_TRACE_NAMES:
        raise TraceReadError(f"{path}: the scenario record names {len(names)} {key}; a trace holds at most "
                             f"{MAX_TRACE_NAMES}: not a physics-scenarios trace")  # fmt: skip
    return [str(n) for n in names]


#: the scenario record's JSON values and their shapes, checked when it is read: what reports read from them
#: (json.loads in the report, the scene, the causes) then never meets a malformed value
_SCENARIO_JSON = {tf.KEY_BODIES: str, tf.KEY_JOINTS: str, tf.KEY_STATE: str, tf.KEY_ASSERTED: str,
                  tf.KEY_BODY_SPECS: dict, tf.KEY_JOINT_SPECS: dict, "overrides": None,
                  tf.KEY_ENGINE_SETTINGS: None}  # fmt: skip


def _check_scenario_json(path: Path, metadata: dict[str, str]) -> None:
    for key, item in _SCENARIO_JSON.items():
        if key not in metadata:
            continue
        try:
            value = _json(metadata[key])
        except ValueError as exc:
            raise TraceReadError(f"{path} is not a physics-scenarios trace: its scenario record's {key!r} is not "
                                 f"JSON ({exc})") from exc  # fmt: skip
        shape = dict if key == tf.KEY_ENGINE_SETTINGS else list
        if not isinstance(value, shape) or (item is not None and not all(isinstance(v, item) for v in value)):
            kind = "an object" if shape is dict else f"a list of {'names' if item is str else 'objects'}"
            raise TraceReadError(f"{path} is not a physics-scenarios trace: its scenario record's {key!r} is not "
                                 f"{kind}")  # fmt: skip


def _check_summary(path: Path, metadata: dict[str, dict[str, str]]) -> None:
    text = metadata.get(tf.METADATA_RESULT, {}).get(tf.KEY_SUMMARY)
    if not text:
        return
    try:
        summary = _json(text)
    except ValueError as exc:
        raise TraceReadError(f"{path} is not a physics-scenarios trace: its summary is not JSON ({exc})") from exc
    if not isinstance(summary, dict):
        raise TraceReadError(f"{path} is not a physics-scenarios trace: its summary is not a JSON object")


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
            for record in _records(f, os.fstat(f.fileno()).st_size, recover, path):
                if isinstance(record, Damage):
                    stop_reason = "; ".join(filter(None, [stop_reason, str(record)]))
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
                        decoder = MessageDecoder(_names(path, scenario, tf.KEY_BODIES),
                                                 _names(path, scenario, tf.KEY_JOINTS))  # fmt: skip
                    decoder.add(ch.topic, schemas.get(ch.schema_id), ch.message_encoding, record.log_time / 1e9,
                                record.data)  # fmt: skip
                elif isinstance(record, Schema):
                    check_schema(record)
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Metadata):
                    metadata[record.name] = dict(record.metadata)
                    if record.name == tf.METADATA_SCENARIO:
                        _check_format(path, metadata[record.name])
                        _check_scenario_json(path, metadata[record.name])
                elif isinstance(record, Attachment):
                    attachments.append(AttachmentInfo(record.name, record.media_type, len(record.data), record.data))
                elif isinstance(record, Footer):
                    complete = True
    except OSError as exc:
        raise TraceReadError(f"cannot read {path}: {exc.strerror or exc}") from exc
    except TraceReadError:
        raise
    except Exception as exc:  # noqa: BLE001 - a garbage schema, record or JSON: the file is not one of ours
        raise TraceReadError(f"{path} is not a physics-scenarios trace: {type(exc).__name__}: {exc}"[:500]) from exc
    if stop_reason and not metadata and not channels:
        raise TraceReadError(f"{path} holds no readable trace: {stop_reason}")
    _check_summary(path, metadata)
    if not complete and not recover:
        raise TraceReadError(f"{path} has no footer (unfinished); read what it holds with recover=True "
                             "(`scenario inspect --recover`)")
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
        sensor_times=np.array(decoded.sensor_times),
        sensors=_sensors(metadata, decoded.sensors),
    )


def _sensors(metadata: dict[str, dict[str, str]], by_field: dict[str, list[float]]) -> dict[str, np.ndarray]:
    """/sensors by quantity name: the trace's list of them (KEY_SENSORS) in field order."""
    try:
        names = json.loads(metadata.get(tf.METADATA_SCENARIO, {}).get(tf.KEY_SENSORS, "[]"))
    except json.JSONDecodeError:
        names = []
    fields = {tf.sensor_field(str(n)): str(n) for n in names}
    return {fields[f]: np.asarray(v, dtype=float) for f, v in by_field.items() if f in fields}
