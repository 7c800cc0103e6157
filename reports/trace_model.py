"""What :func:`reports.trace_reader.read_trace` returns: the :class:`Trace` with its per-body and per-joint
series, its records (events, logs, sounds, verdicts, attachments) and channels, and the reader's error.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

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
    "trace_json",
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
        return trace_json(text) if text else {}  # checked when the trace was read

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


def trace_json(text: str) -> Any:
    """JSON from a trace; nesting too deep to parse is refused like malformed text."""
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError("JSON nested too deeply") from None
