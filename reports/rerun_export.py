"""A trace as a native Rerun recording (``.rrd``), built from the MCAP trace with the rerun-sdk.

What the recording holds (entity paths; every time on the ``sim_time`` timeline, a duration in simulated
seconds):

* ``/world/<body>`` for every body and robot link: its shapes (:mod:`reports.rerun_scene`) and its pose at
  every recorded step (``Transform3D``: translation, quaternion); ``/world`` is Z-up;
* ``/asserted/<unit>/<quantity>``: one ``Scalars`` series per quantity the scenario's assertions read (the
  trace's ``asserted`` metadata: ``crate_4.pos.z``, ``box.speed``, ``slider.position``, ``state.door_open``,
  ``contact(box, door)``), grouped by unit;
* ``/forces/joints/<joint>`` (motor force or torque) and ``/forces/contacts/<a> - <b>`` (normal force, 0 while
  apart) for every joint and every pair that touched;
* ``/world/contact_points``: a trace's contact points (``trace: {contact_points: true}``) as ``Arrows3D`` at
  every recorded step (:mod:`reports.rerun_contacts`);
* ``/log/<logger>``: the trace's /log as ``TextLog`` (events, handler logs, sounds, each verdict when it was
  decided, the summary);
* a blueprint: the 3D view (collision solids hidden), one time-series view per unit of the asserted
  quantities, the forces, and the log.

Deterministic: the recording id is derived from the trace's bytes (a UUID5 of their SHA-256), no property
carries the wall clock, and the data are sent as columns (no ``log_time``/``log_tick`` timelines). The same
trace gives the same stores, entities, components and values; the file's bytes still differ between two
exports, because the SDK mints every chunk's and row's id (a TUID) from the clock.
"""

from __future__ import annotations

import hashlib
import json
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from reports import trace_format as tf
from reports.rerun_contacts import read_arrows, send_arrows
from reports.rerun_scene import WORLD, body_path, scene_entities
from reports.scene3d.framing import frame_camera, moving_bodies
from reports.scene3d.model import SceneModel, scene_model
from reports.trace_reader import Trace, read_trace

__all__ = ["APPLICATION_ID", "TIMELINE", "RerunExportError", "Series", "asserted_series", "export_rerun",
           "recording_id"]  # fmt: skip

APPLICATION_ID = "physics-scenarios"
TIMELINE = "sim_time"
ASSERTED, FORCES, LOG = "asserted", "forces", "log"
#: a unit's entity path part (a path part cannot hold "/" unescaped)
UNIT_PARTS = {"m": "m", "m/s": "m_per_s", "rad": "rad", "rad/s": "rad_per_s", "N": "N", "N·m": "N_m", "J": "J",
              "1": "1", "m or rad": "m_or_rad", "N·s": "N_s", "N·m·s": "N_m_s"}  # fmt: skip
_BODY_UNITS = {"pos": "m", "vel": "m/s", "angvel": "rad/s", "quat": "1"}
_LEVELS = {"debug": "DEBUG", "info": "INFO", "warning": "WARN", "warn": "WARN", "error": "ERROR", "fatal": "CRITICAL"}


class RerunExportError(Exception):
    """The recording cannot be written (rerun-sdk missing, or the file cannot be written)."""


@dataclass(frozen=True)
class Series:
    """One plotted quantity: its name, unit, and values at ``times`` (seconds)."""

    name: str
    unit: str
    times: np.ndarray
    values: np.ndarray


def recording_id(path: Path) -> str:
    """The recording id of a trace's export: a UUID5 of the trace's SHA-256 (same trace, same id)."""
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    return str(uuid.uuid5(uuid.NAMESPACE_URL, f"physics-scenarios:trace:{digest}"))


def _joint_kinds(trace: Trace) -> dict[str, str]:
    try:
        specs = json.loads(trace.scenario.get(tf.KEY_JOINT_SPECS, "[]"))
    except json.JSONDecodeError:
        return {}
    return {str(s.get("name")): str(s.get("kind")) for s in specs if isinstance(s, dict)}


def _joint_unit(kind: str | None, field: str) -> str:
    linear = kind == "slider"
    if field == "position":
        return "m" if linear else "rad" if kind is not None else "m or rad"
    if field == "velocity":
        return "m/s" if linear else "rad/s"
    return "N" if linear else "N·m"


def _contact_force(trace: Trace, a: str, b: str) -> np.ndarray:
    """The normal force between ``a`` and ``b`` at each recorded step of ``trace.times`` (0 while apart)."""
    force = np.zeros(len(trace.times))
    step = {float(t): k for k, t in enumerate(trace.times)}
    for t, pairs in trace.contacts:
        k = step.get(float(t))
        if k is not None:
            force[k] += sum(float(p.get("normal_force", 0.0)) for p in pairs if {p.get("a"), p.get("b")} == {a, b})
    return force


def _one(trace: Trace, name: str, kinds: dict[str, str]) -> Series | None:
    """The series of one asserted quantity, or None where the trace cannot give it (text state, energy)."""
    if name.startswith("contact(") and name.endswith(")"):
        a, _, b = name[len("contact(") : -1].partition(", ")
        return Series(name, "N", trace.times, _contact_force(trace, a, b))
    if name in trace.sensors:  # a sensor quantity, from /sensors
        return Series(name, tf.sensor_unit(name), trace.sensor_times, trace.sensors[name])
    head, _, field = name.rpartition(".")
    if head in trace.joints:
        times, values = trace.series(f"{head}.{'motor_force' if field == 'force' else field}")
        return Series(name, _joint_unit(kinds.get(head), field), times, values)
    if field == "speed" and head in trace.bodies:
        return Series(name, "m/s", trace.times, np.linalg.norm(trace.bodies[head].vel, axis=1))
    if head.startswith("state.") or name.startswith("state."):
        times, values = trace.series(name)
        if values.dtype.kind not in "biuf":
            return None  # a text variable: its changes are in the log and on /state
        return Series(name, "1", times, values.astype(float))
    try:
        times, values = trace.series(name)
    except KeyError:
        return None
    return Series(name, _BODY_UNITS.get(name.split(".")[-2], "1"), times, values)


def asserted_series(trace: Trace) -> tuple[list[Series], list[str]]:
    """(the series of every asserted quantity the trace can give, the names it cannot) from the trace's
    ``asserted`` metadata (empty for a trace written before it)."""
    try:
        names = [str(n) for n in json.loads(trace.scenario.get(tf.KEY_ASSERTED, "[]"))]
    except json.JSONDecodeError:
        names = []
    kinds = _joint_kinds(trace)
    found, missing = [], []
    for name in names:
        series = _one(trace, name, kinds)
        if series is None:
            missing.append(name)
        else:
            found.append(series)
    return found, missing


def _force_series(trace: Trace) -> list[Series]:
    kinds = _joint_kinds(trace)
    out = [Series(j, _joint_unit(kinds.get(j), "force"), trace.joint_times, s.motor_force)
           for j, s in trace.joints.items()]  # fmt: skip
    pairs = dict.fromkeys(tuple(sorted((str(p.get("a")), str(p.get("b"))))) for _, ps in trace.contacts for p in ps)
    for a, b in pairs:
        out.append(Series(f"{a} - {b}", "N", trace.times, _contact_force(trace, a, b)))
    return out


def _duration(times: Any) -> np.ndarray:
    """Simulated seconds as the integer nanoseconds the trace's log times are (rerun truncates a float's
    nanoseconds: 2.01 s would become 2.009999999 s)."""
    return np.round(np.asarray(times, dtype=float) * 1e9).astype(np.int64).astype("timedelta64[ns]")


def _send_series(rec: Any, path: str, series: Series) -> None:
    import rerun as rr

    if not len(series.times):
        return
    rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=_duration(series.times))],
                     columns=rr.Scalars.columns(scalars=np.asarray(series.values, dtype=float)))  # fmt: skip


def _send_poses(rec: Any, trace: Trace) -> None:
    import rerun as rr

    for name, body in trace.bodies.items():
        keep = np.isfinite(body.pos).all(axis=1) & np.isfinite(body.quat).all(axis=1)
        if not keep.any():
            continue
        rec.send_columns(
            body_path(name), indexes=[rr.TimeColumn(TIMELINE, duration=_duration(trace.times[keep]))],
            columns=rr.Transform3D.columns(translation=body.pos[keep], quaternion=body.quat[keep][:, [1, 2, 3, 0]]),
        )  # fmt: skip


def _send_scene(rec: Any, model: SceneModel) -> None:
    import rerun as rr

    rec.log(WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for t, path, archetypes in scene_entities(model):
        batches = [b for archetype in archetypes for b in archetype.as_component_batches()]
        columns = [b.partition([len(b.as_arrow_array())]) for b in batches]  # one row at t: the whole batch
        rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=_duration([t]))], columns=columns)


def _send_logs(rec: Any, trace: Trace) -> None:
    import rerun as rr

    by_logger: dict[str, list[Any]] = {}
    for entry in trace.logs:
        by_logger.setdefault(entry.name or "log", []).append(entry)
    for logger, entries in sorted(by_logger.items()):
        rec.send_columns(
            str(rr.new_entity_path([LOG, logger])),
            indexes=[rr.TimeColumn(TIMELINE, duration=_duration([e.t for e in entries]))],
            columns=rr.TextLog.columns(text=[e.message for e in entries],
                                       level=[_LEVELS.get(e.level, "INFO") for e in entries]),
        )  # fmt: skip


def _unit_path(root: str, unit: str, name: str) -> str:
    import rerun as rr

    return str(rr.new_entity_path([root, UNIT_PARTS.get(unit, unit), name]))


def _eye(model: SceneModel) -> Any:
    """The 3D view's eye where the report's pictures put their camera (reports.scene3d.framing: every moving
    body in view over the whole run), looking at the middle of where they go; Z up. Without it Rerun frames
    everything, and a 40 m ground plane leaves a robot arm a few pixels wide."""
    import rerun.blueprint as rrb

    cam = frame_camera([model])
    moving = moving_bodies([model]) or [b for b in model.bodies if model.shape.get(b) != "plane"]
    points = [t.pos[np.isfinite(t.pos).all(axis=1)] for b in moving if (t := model.tracks.get(b)) is not None]
    cloud = np.vstack(points) if points and sum(len(p) for p in points) else np.zeros((1, 3))
    centre = (cloud.min(axis=0) + cloud.max(axis=0)) / 2
    _, forward, _ = cam.axes()
    target = np.asarray(cam.pos) + forward * max(float((centre - np.asarray(cam.pos)) @ forward), 0.1)
    return rrb.EyeControls3D(kind="Orbital", position=list(cam.pos), look_target=target.tolist(), eye_up=[0, 0, 1])


def _blueprint(units: Sequence[str], force_units: Sequence[str], bodies: Sequence[str], model: SceneModel) -> Any:
    import rerun.blueprint as rrb

    hidden = {body_path(b, "collision"): rrb.EntityBehavior(visible=False) for b in bodies}
    scene = rrb.Spatial3DView(origin=f"/{WORLD}", name="scene", overrides=hidden,  # type: ignore[arg-type]
                              eye_controls=_eye(model))  # fmt: skip
    plots = [rrb.TimeSeriesView(origin=f"/{ASSERTED}/{UNIT_PARTS.get(u, u)}", name=f"asserted ({u})") for u in units]
    plots += [rrb.TimeSeriesView(origin=f"/{FORCES}/{UNIT_PARTS.get(u, u)}", name=f"joint and contact forces ({u})")
              for u in force_units]  # fmt: skip
    log = rrb.TextLogView(origin=f"/{LOG}", name="log")
    right = rrb.Vertical(*plots, log) if plots else log
    return rrb.Blueprint(rrb.Horizontal(scene, right, column_shares=[3, 2]),
                         rrb.TimePanel(timeline=TIMELINE), collapse_panels=False)  # fmt: skip


def export_rerun(trace_path: Path, out: Path, trace: Trace | None = None) -> tuple[Path, list[str]]:
    """Write ``out`` (.rrd) from the trace at ``trace_path``; returns it and the asserted quantities it could
    not plot (a text state variable, a body's energy). Raises :class:`RerunExportError`."""
    try:
        import rerun as rr
    except ImportError as exc:
        raise RerunExportError("rerun-sdk is not installed (pip install '.[viewers]')") from exc
    trace = trace if trace is not None else read_trace(trace_path)
    asserted, missing = asserted_series(trace)
    forces = _force_series(trace)
    units = list(dict.fromkeys(s.unit for s in asserted))
    force_units = list(dict.fromkeys(s.unit for s in forces))
    model = scene_model(trace)
    rec = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id(trace_path), send_properties=False)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        rec.save(out, default_blueprint=_blueprint(units, force_units, list(trace.bodies), model))
    except (OSError, RuntimeError) as exc:
        raise RerunExportError(f"cannot write {out}: {exc}") from exc
    scenario = trace.scenario
    rec.send_recording_name(" · ".join(scenario.get(k, "?") for k in (tf.KEY_NAME, tf.KEY_VARIANT, tf.KEY_BACKEND)))
    _send_scene(rec, model)
    _send_poses(rec, trace)
    for s in asserted:
        _send_series(rec, _unit_path(ASSERTED, s.unit, s.name), s)
    for s in forces:
        _send_series(rec, _unit_path(FORCES, s.unit, s.name), s)
    _send_logs(rec, trace)
    arrows = read_arrows(trace_path) if tf.TOPIC_CONTACT_POINTS in trace.channels else None
    if arrows is not None:
        send_arrows(rec, arrows, _duration, TIMELINE)
    rec.flush()
    rec.disconnect()
    if not out.exists():
        raise RerunExportError(f"rerun-sdk wrote no {out}")
    return out, missing
