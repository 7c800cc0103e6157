"""The MCAP trace writer: the only writer-side user of an MCAP writer.

Layout, topics and metadata: :mod:`reports.trace_format`. The container is written by the official
Foxglove SDK's native (Rust) MCAP writer (``foxglove-sdk``), zstd level 1 chunks, while the run goes on
(memory constant in the duration), to ``<path>.partial`` through an unbuffered sink of ours
(:mod:`runner.trace.sink`), so a finished chunk is in the operating system at once; a chunk closes when it
exceeds ``chunk_size`` bytes and after the first step at or past each multiple of ``flush_interval``
simulated seconds, which bounds what a hard kill loses. The scenario record is built by
:mod:`runner.trace.records`. ``finish()`` writes the ``result`` record and the summary, then renames the
file to ``<path>``. Messages are encoded by :class:`runner.trace.encoder.TraceEncoder` (protobuf; the
per-step ones through serialised templates). Why this writer and level: docs/trace-format.md, "Cost".

The SDK logs a failed sink write as a warning instead of raising it; the sink keeps the first failure and
every call here re-raises it, so a full disk still ends the run with its error (docs/reliability.md).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, TypeVar

import foxglove
from foxglove.mcap import MCAPCompression, MCAPWriteOptions

from backends.types import BodyStates, Contact, ContactPoint, JointStates
from reports import trace_format as tf
from runner.errors import TraceError
from runner.trace import contact_arrows, output
from runner.trace import foxglove as fx
from runner.trace import proto as pb
from runner.trace.encoder import TraceEncoder, dumps, verdict_text
from runner.trace.records import TraceMeta, finish_on_exit, scenario_record
from runner.trace.repeats import EventRuns
from runner.trace.scene import SolidVisual, scene_entities
from runner.trace.sink import open_partial
from runner.trace.sounds import SoundBank

# TraceMeta (runner.trace.records) and SolidVisual (runner.trace.scene) are the writer's inputs, re-exported
__all__ = ["COMPRESSION_THREADS", "ZSTD_LEVEL", "SolidVisual", "TraceMeta", "TraceWriter"]

_T = TypeVar("_T")

#: zstd level of the chunks: level 1 writes 0.1-0.2 us/body/step less than level 3 (the SDK's default) for
#: 8-20 % more bytes, which keeps the trace well under half of format 1 (bench/results-encoding.md)
ZSTD_LEVEL = 1
#: zstd runs in one SDK thread beside the run, so the step loop's thread pays encoding and hand-over only
#: (ODE's pile: 0.51 -> 0.24 us/body/step of the run's thread; bench/results-encoding.md). zstd's output
#: depends on its input and parameters, the worker count included, never on timing: a fixed count keeps
#: "same scenario, backend and engine version => same bytes" (checked by the bench and tests/trace).
COMPRESSION_THREADS = 1


class TraceWriter:
    """Writes one run's trace; a context manager that finishes the trace whatever happens.

    ``__exit__`` after an exception finishes with status "interrupted" (KeyboardInterrupt, SystemExit),
    "engine-failure" (EngineFailure) or "error"; on a clean exit without ``finish()`` it records
    "error". ``force=False`` refuses to overwrite an existing trace or partial trace.
    """

    def __init__(
        self,
        path: Path,
        meta: TraceMeta,
        *,
        force: bool = True,
        chunk_size: int = 1024 * 1024,
        flush_interval: float = 1.0,
    ) -> None:
        self.path = Path(path)
        self.partial_path = self.path.with_name(self.path.name + tf.PARTIAL_SUFFIX)
        self.meta = meta
        self._force = force
        self._names = [b.name for b in meta.bodies]
        self._joint_names = [j.name for j in meta.joints]
        if len(set(self._names)) != len(self._names) or len(set(self._joint_names)) != len(self._joint_names):
            raise ValueError("body and joint names must be unique")
        if set(meta.extra) & set(tf.SCENARIO_KEYS):
            raise ValueError(f"TraceMeta.extra must not redefine {sorted(set(meta.extra) & set(tf.SCENARIO_KEYS))}")
        self._flush_ns = max(1, round(flush_interval * 1e9))
        self._next_flush_ns = self._flush_ns
        self._last_ns = 0
        self._steps = 0
        self._final: Path | None = None
        self._closed = False
        self._scene_sent = False
        self._encoder = TraceEncoder(self._names, self._joint_names)
        self._runs = EventRuns(meta.dt)  # events delivered on every step: one Log line per run
        self._sounds = SoundBank()
        self._sink = open_partial(self.path, self.partial_path, self._force)
        self._context = foxglove.Context()  # this trace's channels reach this trace's writer only
        try:
            options = MCAPWriteOptions(
                compression=MCAPCompression.Zstd, compression_level=ZSTD_LEVEL, compression_threads=COMPRESSION_THREADS,
                profile=tf.PROFILE, chunk_size=chunk_size, disable_seeking=True,
            )  # fmt: skip
            self._writer = self._sdk(foxglove.open_mcap, self._sink, context=self._context, writer_options=options)
            self._channels: dict[str, foxglove.Channel] = {}
            self._register_all()
            self._sdk(self._writer.write_metadata, tf.METADATA_SCENARIO, scenario_record(meta))
        except BaseException as exc:
            self._abandon()
            if self._sink.failed is not None:  # the disk was full before the scenario record was whole:
                with contextlib.suppress(OSError):  # nothing to recover, no 0-byte .partial left behind
                    self.partial_path.unlink()
            if isinstance(exc, OSError):
                raise output.write_error(exc, f"trace {self.partial_path}") from exc
            raise

    # ---- opening ---------------------------------------------------------------------------------

    def _sdk(self, call: Callable[..., _T], *args: Any, **kwargs: Any) -> _T:
        """``call(*args, **kwargs)`` on the SDK writer; a failed write raises the sink's own error (the SDK's
        RuntimeError names no cause), any other SDK error a TraceError."""
        try:
            result = call(*args, **kwargs)
        except RuntimeError as exc:
            self._sink.check()
            raise TraceError(f"cannot write trace {self.partial_path}: {exc}") from exc
        self._sink.check()
        return result

    def _register(self, topic: str, schema_name: str, schema_data: bytes) -> None:
        """A channel of this trace; the SDK writes its schema and channel records before its first message."""
        schema = foxglove.Schema(name=schema_name, encoding=tf.SCHEMA_ENCODING, data=schema_data)
        self._channels[topic] = foxglove.Channel(
            topic, schema=schema, message_encoding=tf.MESSAGE_ENCODING, context=self._context
        )

    def _register_all(self) -> None:
        for channel in self._encoder.channels():
            self._register(channel.topic, channel.schema_name, channel.schema_data)

    # ---- writing ---------------------------------------------------------------------------------

    def _ns(self, t: float) -> int:
        if self._closed:
            raise TraceError(f"trace {self.path} is already finished")
        if not math.isfinite(t) or t < 0.0:
            raise ValueError(f"simulated time must be finite and >= 0, got {t!r}")
        ns = round(t * 1e9)
        self._sum_up_runs(self._runs.ended(ns, self._last_ns))
        self._last_ns = max(self._last_ns, ns)
        return ns

    def _sum_up_runs(self, summaries: Sequence[tuple[int, str]]) -> None:
        for ns, text in summaries:
            self._log(ns, tf.LOG_LEVELS["info"], text, tf.LOGGER_EVENT)

    def _write(self, topic: str, ns: int, data: bytes) -> None:
        self._channels[topic].log(data, log_time=ns)
        if self._sink.failed is not None:
            raise self._sink.failed

    def _log(self, ns: int, level: int, message: str, name: str) -> None:
        self._write(tf.TOPIC_LOG, ns, self._encoder.log(ns, level, message, name))

    def attach(self, name: str, data: bytes, media_type: str) -> None:
        """Attach a file (the scenario, its sounds); a ``sounds/<name>.wav`` also feeds /audio."""
        if self._closed:
            raise TraceError(f"trace {self.path} is already finished")
        self._sdk(self._writer.attach, log_time=self._last_ns, create_time=0, name=name, media_type=media_type,
                  data=bytes(data))  # fmt: skip
        self._sounds.add(name, bytes(data))

    def scene(self, t: float, solids: Sequence[SolidVisual] = (), scales: Mapping[str, float] | None = None) -> None:
        """Publish every body as it is drawn, its collision shapes, the joints (first call) and the given
        solids (already scaled, body frame): runner.trace.scene.

        ``scales[name]`` multiplies the *compiled* shape (which already includes the start scale), so
        pass ``current scale / start scale``; default 1. Entities keep their ids ("body/<name>",
        "collision/<name>", "joint/<name>", "solid/<body>/<node>"), so a later call replaces them; pass the
        solids again to resize them.
        """
        ns = self._ns(t)
        joints = () if self._scene_sent else self.meta.joints
        self._scene_sent = True
        by_topic = scene_entities(ns, self.meta.bodies, joints, scales)
        for s in solids:
            if s.body not in self._names:
                raise ValueError(f"solid {s.node!r} is attached to unknown body {s.body!r}")
            prims = fx.solid_primitives(s.kind, s.center, s.radius, s.size, s.vertices)
            by_topic[tf.TOPIC_SCENE].append(fx.entity(ns, s.body, f"solid/{s.body}/{s.node}", {"solid": s.node},
                                                      **prims))  # fmt: skip
        for topic, entities in by_topic.items():
            self._write(topic, ns, self._encoder.scene(entities))

    def step(
        self,
        t: float,
        states: BodyStates,
        joints: JointStates,
        contacts: Sequence[Contact],
        state_vars: Mapping[str, bool | float | str],
    ) -> None:
        ns = self._ns(t)
        enc = self._encoder
        transforms, bodies = enc.transforms_and_bodies(ns, states.rows())
        self._write(tf.TOPIC_TF, ns, transforms)
        for topic, data in zip(enc.body_topics, bodies, strict=True):
            self._write(topic, ns, data)
        if self._joint_names:
            messages = enc.joints_messages(joints.position, joints.velocity, joints.motor_force)
            for topic, data in zip(enc.joint_topics, messages, strict=True):
                self._write(topic, ns, data)
        self._write(tf.TOPIC_CONTACTS, ns, enc.contacts_message(contacts))
        if state_vars:
            if tf.TOPIC_STATE not in self._channels:
                channel = enc.state_channel(state_vars)
                self._register(channel.topic, channel.schema_name, channel.schema_data)
            self._write(tf.TOPIC_STATE, ns, enc.state_message(state_vars))
        self._steps += 1
        if ns >= self._next_flush_ns:
            self._sdk(self._writer.flush)
            self._next_flush_ns = (ns // self._flush_ns + 1) * self._flush_ns

    def contact_points(self, t: float, points: Sequence[ContactPoint]) -> None:
        """The step's contact points as arrows on /contact_points (runner.trace.contact_arrows), at the scale
        the scenario record states; the channel exists only in traces that ask for points."""
        scale = self.meta.extra.get(contact_arrows.KEY_SCALE)
        if scale is None:
            raise ValueError(f"contact points need the scenario record's {contact_arrows.KEY_SCALE!r}")
        if tf.TOPIC_CONTACT_POINTS not in self._channels:
            update = fx.SceneUpdate
            self._register(tf.TOPIC_CONTACT_POINTS, update.DESCRIPTOR.full_name, pb.schema_data(update))
        ns = self._ns(t)
        message = contact_arrows.scene_update(ns, points, float(scale))
        self._write(tf.TOPIC_CONTACT_POINTS, ns, message.SerializeToString(deterministic=True))

    def sensors(self, t: float, values: Sequence[float]) -> None:
        """/sensors at a recorded step: the values of the sensor quantities ``meta.extra[KEY_SENSORS]`` lists,
        in that order (the channel is registered with the first)."""
        ns = self._ns(t)
        if tf.TOPIC_SENSORS not in self._channels:
            names = json.loads(self.meta.extra.get(tf.KEY_SENSORS, "[]"))
            channel = self._encoder.sensors_channel(names)
            self._register(channel.topic, channel.schema_name, channel.schema_data)
        self._write(tf.TOPIC_SENSORS, ns, self._encoder.sensors_message(values))

    def event(self, t: float, name: str, source: str, detail: Mapping[str, Any] | None = None) -> None:
        """Every delivery on /events; on /log, those that start a run (runner/trace/repeats.py)."""
        ns = self._ns(t)
        self._write(tf.TOPIC_EVENTS, ns, self._encoder.event(t, name, source, detail))
        if self._runs.deliver(ns, name, source):
            extra = f" {dumps(detail, ensure_ascii=False)}" if detail else ""
            self._log(ns, tf.LOG_LEVELS["info"], f"{name} ({source}){extra}", tf.LOGGER_EVENT)

    def log(self, t: float, level: str, message: str, name: str = tf.LOGGER_SCENARIO) -> None:
        code = tf.LOG_LEVELS.get(level.lower())
        if code is None:
            raise ValueError(f"unknown log level {level!r}; expected one of {sorted(tf.LOG_LEVELS)}")
        self._log(self._ns(t), code, message, name)

    def sound(self, t: float, name: str, action: str, offset: float = 0.0, volume: float = 1.0) -> None:
        if action not in tf.SOUND_ACTIONS:
            raise ValueError(f"unknown sound action {action!r}; expected one of {sorted(tf.SOUND_ACTIONS)}")
        ns = self._ns(t)
        self._write(tf.TOPIC_SOUNDS, ns, self._encoder.sound(t, name, action, offset, volume))
        if action == "start":
            clip = self._sounds.clip(name, offset, volume)
            if clip is not None:
                self._write(tf.TOPIC_AUDIO, ns, self._encoder.audio(ns, *clip))
        text = (
            f"{action} {name}"
            + (f" from {offset:g} s" if offset else "")
            + (f" at volume {volume:g}" if volume != 1.0 else "")
        )
        self._log(ns, tf.LOG_LEVELS["info"], text, tf.LOGGER_SOUND)

    def verdict(self, t: float, verdict: Mapping[str, Any]) -> None:
        """Log one verdict at the time it was decided (/log only; /verdicts gets them all at the end)."""
        level, text = verdict_text(verdict)
        self._log(self._ns(t), tf.LOG_LEVELS[level], text, tf.LOGGER_VERDICT)

    def verdicts(self, t: float, verdicts: Sequence[Mapping[str, Any]]) -> None:
        """Every verdict of the run on /verdicts, and a summary line on /log (after the runs of events)."""
        ns = self._ns(t)
        self._sum_up_runs(self._runs.ended(ns, self._last_ns, everything=True))
        self._write(tf.TOPIC_VERDICTS, ns, self._encoder.verdicts(t, verdicts))
        limits = [
            str(v.get(tf.VERDICT_NAME, "?")) for v in verdicts if v.get("known_limit") and v.get(tf.VERDICT_PASSED)
        ]
        passed = sum(v.get(tf.VERDICT_PASSED) is True for v in verdicts) - len(limits)
        failed = [str(v.get(tf.VERDICT_NAME, "?")) for v in verdicts if v.get(tf.VERDICT_PASSED) is not True]
        text = f"{passed}/{len(verdicts)} assertions passed" + (f"; failed: {', '.join(failed)}" if failed else "")
        text += f"; known limits: {', '.join(limits)}" if limits else ""
        self._log(ns, tf.LOG_LEVELS["error" if failed else "info"], text, tf.LOGGER_VERDICT)

    # ---- finishing -------------------------------------------------------------------------------

    def finish(self, status: str, summary: Mapping[str, Any]) -> Path:
        """Write the result, close the file and give it its final name. Idempotent: returns the path."""
        if self._final is not None:
            return self._final
        if status not in tf.STATUSES:
            raise ValueError(f"unknown status {status!r}; expected one of {sorted(tf.STATUSES)}")
        if self._closed:
            raise TraceError(f"trace {self.path} was abandoned; what was written is in {self.partial_path}")
        result = {
            tf.KEY_STATUS: status,
            tf.KEY_SUMMARY: dumps(summary, sort_keys=True),
            tf.KEY_STEPS: str(self._steps),
            tf.KEY_END_TIME: repr(self._last_ns / 1e9),
        }
        try:
            self._sum_up_runs(self._runs.ended(self._last_ns, self._last_ns, everything=True))
            self._sdk(self._writer.write_metadata, tf.METADATA_RESULT, result)
            self._sdk(self._writer.close)
            self._closed = True
            self._sink.close(sync=True)
        except TraceError:
            self._abandon()
            raise
        except OSError as exc:
            self._abandon()
            raise output.write_error(exc, f"trace {self.partial_path}") from exc
        if not self._force and self.path.exists():
            raise TraceError(f"{self.path} appeared while this run was writing; the trace is in {self.partial_path}")
        try:
            os.replace(self.partial_path, self.path)
        except OSError as exc:
            raise TraceError(f"cannot rename {self.partial_path} to {self.path}: {exc.strerror or exc}") from exc
        self._final = self.path
        return self.path

    def _abandon(self) -> None:
        """Close without finishing: the .partial file stays, readable with recover=True. The SDK writer is
        closed into a sink that discards (it would otherwise finish the file when collected)."""
        self._closed = True
        sink = getattr(self, "_sink", None)
        if sink is None:
            return
        sink.discard()
        writer = getattr(self, "_writer", None)
        if writer is not None:
            with contextlib.suppress(Exception):
                writer.close()
        with contextlib.suppress(OSError):
            sink.close(sync=False)

    def __enter__(self) -> TraceWriter:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if self._final is None and not self._closed:
            finish_on_exit(self, exc)
