"""Reading a trace back: metadata, channels, per-step arrays, events, logs, sounds, verdicts.

The file is read front to back, record by record (:mod:`reports.trace_records`, no summary section needed), so
the same code reads a finished trace and, with ``recover=True``, one cut off by a hard kill or damaged:
a record whose bytes are whole but unreadable (a flipped bit in a chunk) is skipped and reading goes on
after it; a record cut off ends the reading, keeping everything before it. Without ``recover`` a damaged
or unfinished file raises :class:`TraceReadError` ("damaged at byte N"). Anything else that goes wrong
(garbage schemas, JSON, names) is "not a physics-scenarios trace". Messages are decoded by
:mod:`reports.trace_decode` (format 2, protobuf); a trace of another format version is refused with a
message naming it (the metadata's checks: :mod:`reports.trace_checks`). What it returns:
:mod:`reports.trace_model`.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
from mcap.records import Attachment, Channel, Footer, Message, Metadata, Schema

from reports import trace_format as tf
from reports.trace_checks import check_format, check_scenario_json, check_summary, record_names
from reports.trace_chunks import check_schema
from reports.trace_decode import MessageDecoder, body_arrays
from reports.trace_model import (
    AttachmentInfo,
    BodySeries,
    ChannelInfo,
    EventRecord,
    JointSeries,
    LogRecord,
    SoundRecord,
    Trace,
    TraceReadError,
    Verdict,
)
from reports.trace_records import Damage, read_records

# the trace's types (reports.trace_model) are re-exported: reports, commands and tests take them from here
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
            for record in read_records(f, os.fstat(f.fileno()).st_size, recover, path):
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
                        decoder = MessageDecoder(record_names(path, scenario, tf.KEY_BODIES),
                                                 record_names(path, scenario, tf.KEY_JOINTS))  # fmt: skip
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
                        check_format(path, metadata[record.name])
                        check_scenario_json(path, metadata[record.name])
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
    check_summary(path, metadata)
    if not complete and not recover:
        raise TraceReadError(
            f"{path} has no footer (unfinished); read what it holds with recover=True (`scenario inspect --recover`)"
        )
    if tf.METADATA_SCENARIO not in metadata and any(s.encoding == "jsonschema" for s in schemas.values()):
        check_format(path, {})
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
