"""The MCAP trace format: the one place where the writer (runner/trace/) and the readers agree.

Constants, and the one rule both sides compute (:func:`message_parts`); the format is described for users
in docs/trace-format.md. A trace is one MCAP file per run and variant:

* log time and publish time of every message = simulated time in integer nanoseconds
  (``round(t * 1e9)``); nothing in the file comes from the wall clock;
* chunked, zstd-compressed, written while running to ``<path>.partial`` and renamed to ``<path>``
  when finished, so a file under its final name always has a ``result`` metadata record;
* every channel in protobuf (schema encoding ``protobuf``, the schema record a serialised
  ``FileDescriptorSet``): Foxglove's well-known schemas for the 3D, Log and Audio panels
  (``foxglove-schemas-protobuf``), and the project's own messages
  (``runner/trace/proto/physics_scenarios.proto``, plus Bodies, Joints and State generated per trace
  from the scenario's names; a robot's link or joint whose name is not an identifier has the field
  :func:`field_name`, the metadata keeping the name itself).

Per-step numbers on /tf, /bodies, /joints and /contacts are doubles rounded to :data:`VALUE_RESOLUTION`
(NaN and infinities kept), so a body at rest writes identical bytes every step and compresses away.

Format 1 (until physics-scenarios 0.1.0) was JSON (``jsonschema``/``json``) with LZ4; readers name its
version and refuse it (:data:`TRACE_FORMAT_VERSION`, metadata key :data:`KEY_TRACE_FORMAT`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Final

#: bump when the layout of a channel or a metadata record changes meaning
TRACE_FORMAT_VERSION: Final = 2
#: what each earlier format was, for the reader's refusal message
PREVIOUS_FORMATS: Final = {1: "JSON channels with LZ4 chunks (physics-scenarios 0.1.0 and earlier)"}

#: MCAP header
PROFILE: Final = ""
LIBRARY: Final = "physics-scenarios"  # the header of traces written by the pure-Python mcap writer
#: how the header of a trace written by the Foxglove SDK begins (the SDK sets it: its name and version)
SDK_LIBRARY: Final = "foxglove-sdk"

#: file naming
FILE_SUFFIX: Final = ".mcap"
PARTIAL_SUFFIX: Final = ".partial"  # appended to the final name while writing
#: the Foxglove layout written beside the traces (runner/trace/layout.py)
LAYOUT_FILE: Final = "foxglove-layout.json"


def scenario_layout_file(scenario: str) -> str:
    """The layout of one scenario, beside the command's combined one: ``<scenario>.foxglove-layout.json``
    (another scenario run into the same folder never replaces it)."""
    return f"{scenario}.{LAYOUT_FILE}"


#: encodings
SCHEMA_ENCODING: Final = "protobuf"
MESSAGE_ENCODING: Final = "protobuf"

#: absolute resolution of per-step values on /tf, /bodies, /joints and /contacts (SI units)
VALUE_RESOLUTION: Final = 1e-9

#: the root frame of the transform tree; every body's frame is its name, parented to it
WORLD_FRAME: Final = "world"

#: the columns of one body's row of per-step values (backends.types.BodyStates.rows())
BODY_ROW: Final = ("pos.x", "pos.y", "pos.z", "quat.w", "quat.x", "quat.y", "quat.z",
                   "vel.x", "vel.y", "vel.z", "angvel.x", "angvel.y", "angvel.z")  # fmt: skip

# ---- topics -------------------------------------------------------------------------------------
TOPIC_TF: Final = "/tf"  # foxglove.FrameTransforms: every body's pose, one message per step
TOPIC_SCENE: Final = "/scene"  # foxglove.SceneUpdate, at t=0 and when a visual scale changes
TOPIC_SCENE_COLLISION: Final = "/scene/collision"  # foxglove.SceneUpdate: collision shapes of bodies with visuals
TOPIC_LOG: Final = "/log"  # foxglove.Log: events, handler logs, sounds, verdicts (when decided), summary
TOPIC_BODIES: Final = "/bodies"  # physics_scenarios.Bodies: box.vel.{x,y,z}, box.angvel.{x,y,z} per step
TOPIC_JOINTS: Final = "/joints"  # physics_scenarios.Joints: slider.{position,velocity,motor_force} per step
TOPIC_CONTACTS: Final = "/contacts"  # physics_scenarios.Contacts: count, pairs[{a,b,points,depth,normal_force}]
#: foxglove.SceneUpdate: each recorded step's contact points as arrows (only with `trace: {contact_points: true}`)
TOPIC_CONTACT_POINTS: Final = "/contact_points"
TOPIC_STATE: Final = "/state"  # physics_scenarios.State: one field per state variable, per step
#: physics_scenarios.Sensors: one double per sensor quantity the scenario reads (KEY_SENSORS), per step
TOPIC_SENSORS: Final = "/sensors"
TOPIC_EVENTS: Final = "/events"  # physics_scenarios.Event: time, name, source, detail
TOPIC_SOUNDS: Final = "/sounds"  # physics_scenarios.Sound: time, name, action, offset, volume
TOPIC_AUDIO: Final = "/audio"  # foxglove.RawAudio: each sound's samples from where it starts playing
TOPIC_VERDICTS: Final = "/verdicts"  # physics_scenarios.Verdicts: every verdict, at the end

#: top-level fields per /bodies or /joints message. protobuf (upb) lays a message out in at most 65,535 bytes,
#: 8 per message-typed field, and refuses a larger one (measured: 8,064 bodies fit, 8,065 do not); a larger
#: world's bodies continue on /bodies/2, /bodies/3, ... (:func:`message_parts`, :func:`part_topic`)
FIELDS_PER_MESSAGE: Final = 8000


def message_parts(names: Sequence[str]) -> list[list[str]]:
    """``names`` (bodies or joints, CompiledWorld order) split over the messages of /bodies or /joints: in
    order, at most :data:`FIELDS_PER_MESSAGE` top-level fields each, where a robot's members (``arm.link_7``)
    are one field, their robot's. One part (possibly empty) for up to that many fields."""
    parts: list[list[str]] = [[]]
    fields: set[str] = set()  # the current part's top-level fields
    for name in names:
        group = name.partition(".")[0]
        if group not in fields:
            if len(fields) == FIELDS_PER_MESSAGE:
                parts.append([])
                fields = set()
            fields.add(group)
        parts[-1].append(name)
    return parts


_UNSAFE_FIELD_CHARACTER = re.compile(r"[^A-Za-z0-9_]")


def field_name(name: str) -> str:
    """The protobuf field (and Foxglove message-path part) of a robot's link or joint ``name``, which the
    model file may spell any way (``8``, ``pinch site``): every character other than an ASCII letter, digit
    or ``_`` becomes ``_``, and ``_`` goes before a leading digit (``_8``, ``pinch_site``); an identifier is
    its own field. The scenario loader refuses two names of one robot that would share a field
    (runner.language.model_names, the same rule), so readers map names to fields without a table."""
    safe = _UNSAFE_FIELD_CHARACTER.sub("_", name)
    return f"_{safe}" if safe[:1].isdigit() else safe


def sensor_field(name: str) -> str:
    """The field of a sensor quantity on /sensors: its dotted parts, each a :func:`field_name`, joined by
    ``__`` (``shoulder.reaction.torque.y`` -> ``shoulder__reaction__torque__y``, ``hand.pinch site.pos.z`` ->
    ``hand__pinch_site__pos__z``); the writer lists the names in field order (KEY_SENSORS)."""
    return "__".join(field_name(part) for part in name.split("."))


_SENSOR_UNITS = {"kinetic_energy": "J", "momentum": "N·s", "angmom": "N·m·s", "angmom_origin": "N·m·s",
                 "angvel_body": "rad/s", "pos": "m", "vel": "m/s", "angvel": "rad/s", "quat": "1"}  # fmt: skip


def sensor_unit(name: str) -> str:
    """The unit of a sensor quantity (docs/language.md "Sensors"), for plots: N or N·m for a reaction, J, N·s,
    N·m·s, rad/s, m, m/s for a body's or a frame's."""
    parts = name.split(".")
    if "reaction" in parts[1:]:
        return "N" if parts[-2].startswith("force") else "N·m"
    return _SENSOR_UNITS.get(parts[-1], _SENSOR_UNITS.get(parts[-2], "1") if len(parts) > 1 else "1")


def field_path(name: str) -> str:
    """The message path of a body or joint within /bodies or /joints: ``box``, ``arm.link_7``, ``arm._8``
    (a robot's member through its robot's message, with its :func:`field_name`)."""
    group, dot, leaf = name.partition(".")
    return f"{group}.{field_name(leaf)}" if dot else name


def part_topic(topic: str, part: int) -> str:
    """The topic of part ``part`` (from 0) of /bodies or /joints: the topic itself, then ``<topic>/2``, ..."""
    return topic if part == 0 else f"{topic}/{part + 1}"


def parts_by_topic(topic: str, names: Sequence[str]) -> dict[str, tuple[int, list[str]]]:
    """/bodies (or /joints) and its further parts -> (index of the part's first name, the part's names)."""
    out, first = {}, 0
    for k, part in enumerate(message_parts(names)):
        out[part_topic(topic, k)] = (first, part)
        first += len(part)
    return out

# ---- schema names -------------------------------------------------------------------------------
SCHEMA_FRAME_TRANSFORMS: Final = "foxglove.FrameTransforms"
SCHEMA_SCENE_UPDATE: Final = "foxglove.SceneUpdate"
SCHEMA_LOG: Final = "foxglove.Log"
SCHEMA_RAW_AUDIO: Final = "foxglove.RawAudio"
SCHEMA_BODIES: Final = "physics_scenarios.Bodies"
SCHEMA_JOINTS: Final = "physics_scenarios.Joints"
SCHEMA_CONTACTS: Final = "physics_scenarios.Contacts"
SCHEMA_STATE: Final = "physics_scenarios.State"
SCHEMA_EVENT: Final = "physics_scenarios.Event"
SCHEMA_SOUND: Final = "physics_scenarios.Sound"
SCHEMA_VERDICTS: Final = "physics_scenarios.Verdicts"

# ---- field names inside the project's channels --------------------------------------------------
BODY_FIELDS: Final = ("pos", "quat", "vel", "angvel")  # the reader's BodySeries; pos and quat come from /tf
QUAT_KEYS: Final = ("w", "x", "y", "z")  # the reader's quaternions; /tf has Foxglove's x, y, z, w fields
VEC_KEYS: Final = ("x", "y", "z")
JOINT_FIELDS: Final = ("position", "velocity", "motor_force")

# ---- foxglove.Log ---------------------------------------------------------------------------------
#: level name (as the runner passes it) -> foxglove.LogLevel value
LOG_LEVELS: Final = {"unknown": 0, "debug": 1, "info": 2, "warning": 3, "warn": 3, "error": 4, "fatal": 5}
LOG_LEVEL_NAMES: Final = {0: "unknown", 1: "debug", 2: "info", 3: "warning", 4: "error", 5: "fatal"}
#: the Log's `name` field for records the writer makes itself (handler logs pass their own)
LOGGER_SCENARIO: Final = "scenario"
LOGGER_EVENT: Final = "event"
LOGGER_SOUND: Final = "sound"
LOGGER_VERDICT: Final = "verdict"

# ---- sounds ---------------------------------------------------------------------------------------
SOUND_ACTIONS: Final = frozenset({"start", "stop"})

# ---- verdicts: keys the writer and `inspect` look for in each verdict mapping -------------------
VERDICT_NAME: Final = "name"
VERDICT_PASSED: Final = "passed"  # bool
VERDICT_MEASURED: Final = "measured"
VERDICT_EXPECTED: Final = "expected"

# ---- metadata records ---------------------------------------------------------------------------
#: written when the trace is opened
METADATA_SCENARIO: Final = "scenario"
KEY_NAME: Final = "name"
KEY_VARIANT: Final = "variant"
KEY_BACKEND: Final = "backend"
KEY_BACKEND_VERSION: Final = "backend_version"
KEY_ENGINE_SETTINGS: Final = "engine_settings"  # JSON object
KEY_DT: Final = "dt"  # repr of a float
KEY_SUBSTEPS: Final = "substeps"
KEY_DURATION: Final = "duration"
KEY_TOOL_VERSION: Final = "tool_version"
KEY_SCENARIO_SHA256: Final = "scenario_sha256"
KEY_SCENARIO_PATH: Final = "scenario_path"
KEY_SCHEMA_VERSION: Final = "schema_version"
KEY_TRACE_FORMAT: Final = "trace_format"
KEY_BODIES: Final = "bodies"  # JSON list of names, CompiledWorld order
KEY_BODY_SPECS: Final = "body_specs"  # JSON list: name, motion, shape, size, radius, length, mass, color
KEY_JOINTS: Final = "joints"  # JSON list of names
KEY_JOINT_SPECS: Final = "joint_specs"  # JSON list: name, kind, body, other, axis
KEY_STATE: Final = "state"  # JSON list of state variable names
#: JSON list of the quantities the assertions read (runner.compile.asserted): `box.pos.z`, `crate_4.speed`,
#: `slider.position`, `state.door_open`, `contact(box, door)`; absent from traces written before it
KEY_ASSERTED: Final = "asserted"
#: JSON list of the sensor quantities on /sensors, in field order (docs/language.md "Sensors"); absent: none
KEY_SENSORS: Final = "sensors"
SCENARIO_KEYS: Final = (
    KEY_NAME,
    KEY_VARIANT,
    KEY_BACKEND,
    KEY_BACKEND_VERSION,
    KEY_ENGINE_SETTINGS,
    KEY_DT,
    KEY_SUBSTEPS,
    KEY_DURATION,
    KEY_TOOL_VERSION,
    KEY_SCENARIO_SHA256,
    KEY_SCENARIO_PATH,
    KEY_SCHEMA_VERSION,
    KEY_TRACE_FORMAT,
    KEY_BODIES,
    KEY_BODY_SPECS,
    KEY_JOINTS,
    KEY_JOINT_SPECS,
    KEY_STATE,
)

#: written by TraceWriter.finish()
METADATA_RESULT: Final = "result"
KEY_STATUS: Final = "status"
KEY_SUMMARY: Final = "summary"  # JSON object
KEY_STEPS: Final = "steps"  # number of step() calls
KEY_END_TIME: Final = "end_time"  # repr of the last simulated time written

# ---- run status ---------------------------------------------------------------------------------
STATUS_PASSED: Final = "passed"
STATUS_FAILED: Final = "failed"
STATUS_ERROR: Final = "error"
STATUS_INTERRUPTED: Final = "interrupted"
STATUS_ENGINE_FAILURE: Final = "engine-failure"
STATUSES: Final = frozenset({STATUS_PASSED, STATUS_FAILED, STATUS_ERROR, STATUS_INTERRUPTED, STATUS_ENGINE_FAILURE})
#: reader only: the file has no result record (the writer was killed before finish())
STATUS_INCOMPLETE: Final = "incomplete"
