"""The trace's two metadata records: the scenario record (from :class:`TraceMeta`, written when the trace
opens) and the status and summary of the result record when a run ends without one (:func:`exit_status`).

Keys and statuses: :mod:`reports.trace_format`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from backends.errors import EngineFailure
from backends.types import BodySpec, JointSpec
from reports import trace_format as tf
from runner.trace import foxglove as fx
from runner.trace.encoder import dumps

__all__ = ["TraceMeta", "exit_status", "finish_on_exit", "scenario_record"]


@dataclass(frozen=True)
class TraceMeta:
    """What a trace records about its run before the first step: scenario, backend, settings, bodies, joints."""

    scenario: str
    variant: str
    backend: str
    backend_version: str
    engine_settings: Mapping[str, Any]
    dt: float
    substeps: int
    duration: float
    tool_version: str
    scenario_sha256: str
    scenario_path: str
    schema_version: int
    bodies: Sequence[BodySpec]
    joints: Sequence[JointSpec]
    state_names: Sequence[str]
    extra: Mapping[str, str] = field(default_factory=dict)


def scenario_record(meta: TraceMeta) -> dict[str, str]:
    """The scenario record of a trace: the run's identity, its bodies, joints and state, then ``meta.extra``."""
    m = meta
    record = {
        tf.KEY_NAME: m.scenario,
        tf.KEY_VARIANT: m.variant,
        tf.KEY_BACKEND: m.backend,
        tf.KEY_BACKEND_VERSION: m.backend_version,
        tf.KEY_ENGINE_SETTINGS: dumps(m.engine_settings, sort_keys=True),
        tf.KEY_DT: repr(float(m.dt)),
        tf.KEY_SUBSTEPS: str(int(m.substeps)),
        tf.KEY_DURATION: repr(float(m.duration)),
        tf.KEY_TOOL_VERSION: m.tool_version,
        tf.KEY_SCENARIO_SHA256: m.scenario_sha256,
        tf.KEY_SCENARIO_PATH: m.scenario_path,
        tf.KEY_SCHEMA_VERSION: str(m.schema_version),
        tf.KEY_TRACE_FORMAT: str(tf.TRACE_FORMAT_VERSION),
        tf.KEY_BODIES: dumps([b.name for b in m.bodies]),
        tf.KEY_BODY_SPECS: dumps([fx.body_spec_record(b) for b in m.bodies]),
        tf.KEY_JOINTS: dumps([j.name for j in m.joints]),
        tf.KEY_JOINT_SPECS: dumps([asdict(j) for j in m.joints]),
        tf.KEY_STATE: dumps(list(m.state_names)),
    }
    record.update({str(k): str(v) for k, v in m.extra.items()})
    return record


def finish_on_exit(writer: Any, exc: BaseException | None) -> None:
    """Finish a writer left by its run (``__exit__`` of both writers): the status says how the run ended;
    finishing never masks the exception that ended it."""
    status, summary = exit_status(exc)
    if exc is None:
        writer.finish(status, summary)
        return
    try:
        writer.finish(status, summary)
    except Exception:  # noqa: BLE001 - never mask the exception that ended the run
        writer._abandon()


def exit_status(exc: BaseException | None) -> tuple[str, dict[str, Any]]:
    """The status and summary a trace is finished with when its run ends without a result."""
    if exc is None:
        return tf.STATUS_ERROR, {"error": "the run ended without recording a result"}
    if isinstance(exc, KeyboardInterrupt | SystemExit):
        return tf.STATUS_INTERRUPTED, {"error": f"{type(exc).__name__}: {exc}".rstrip(": ")}
    if isinstance(exc, EngineFailure):
        return tf.STATUS_ENGINE_FAILURE, {"error": f"{type(exc).__name__}: {exc}", "body": exc.body, "time": exc.time}
    return tf.STATUS_ERROR, {"error": f"{type(exc).__name__}: {exc}"}
