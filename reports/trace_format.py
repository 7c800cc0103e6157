"""The MCAP trace format: the one place where the writer (runner/trace/writer.py) and the readers agree.

Constants only. A trace is one MCAP file per run and variant:

* log time and publish time of every message = simulated time in integer nanoseconds
  (``round(t * 1e9)``); nothing in the file comes from the wall clock;
* chunked, LZ4-compressed, written while running to ``<path>.partial`` and renamed to ``<path>``
  when finished, so a file under its final name always has a ``result`` metadata record;
* channels in JSON (schema encoding ``jsonschema``): three Foxglove well-known schemas for the 3D,
  Log and Plot panels, plus the project's own plottable channels below.

Per-step numbers on /tf, /bodies, /joints and /contacts (depth, normal force) are written with a
fixed absolute resolution of :data:`VALUE_RESOLUTION` (as ``<integer>e-9`` JSON numbers, ten times
cheaper to format than a float's shortest repr); non-finite values are written as ``null``.
"""

from __future__ import annotations

from typing import Final

#: bump when the layout of a channel or a metadata record changes meaning
TRACE_FORMAT_VERSION: Final = 1

#: MCAP header
PROFILE: Final = ""
LIBRARY: Final = "physics-scenarios"

#: file naming
FILE_SUFFIX: Final = ".mcap"
PARTIAL_SUFFIX: Final = ".partial"  # appended to the final name while writing

#: encodings
SCHEMA_ENCODING: Final = "jsonschema"
MESSAGE_ENCODING: Final = "json"

#: absolute resolution of per-step values on /tf, /bodies, /joints and /contacts (SI units)
VALUE_RESOLUTION: Final = 1e-9

#: the root frame of the transform tree; every body's frame is its name, parented to it
WORLD_FRAME: Final = "world"

# ---- topics -------------------------------------------------------------------------------------
TOPIC_TF: Final = "/tf"  # foxglove.FrameTransforms, every body, one message per step
TOPIC_SCENE: Final = "/scene"  # foxglove.SceneUpdate, at t=0 and when a visual scale changes
TOPIC_LOG: Final = "/log"  # foxglove.Log: events, handler logs, sounds, verdicts
TOPIC_BODIES: Final = "/bodies"  # {"box": {"pos": {x,y,z}, "quat": {w,x,y,z}, "vel": .., "angvel": ..}}
TOPIC_JOINTS: Final = "/joints"  # {"slider": {"position", "velocity", "motor_force"}}
TOPIC_CONTACTS: Final = "/contacts"  # {"count": n, "pairs": [{"a","b","points","depth","normal_force"}]}
TOPIC_STATE: Final = "/state"  # {name: value}
TOPIC_EVENTS: Final = "/events"  # {"time", "name", "source", "detail"}
TOPIC_SOUNDS: Final = "/sounds"  # {"time", "name", "action", "offset", "volume"}
TOPIC_VERDICTS: Final = "/verdicts"  # {"time", "verdicts": [...]}

# ---- schema names -------------------------------------------------------------------------------
SCHEMA_FRAME_TRANSFORMS: Final = "foxglove.FrameTransforms"
SCHEMA_SCENE_UPDATE: Final = "foxglove.SceneUpdate"
SCHEMA_LOG: Final = "foxglove.Log"
SCHEMA_BODIES: Final = "physics_scenarios.Bodies"
SCHEMA_JOINTS: Final = "physics_scenarios.Joints"
SCHEMA_CONTACTS: Final = "physics_scenarios.Contacts"
SCHEMA_STATE: Final = "physics_scenarios.State"
SCHEMA_EVENT: Final = "physics_scenarios.Event"
SCHEMA_SOUND: Final = "physics_scenarios.Sound"
SCHEMA_VERDICTS: Final = "physics_scenarios.Verdicts"

# ---- field names inside the project's channels --------------------------------------------------
BODY_FIELDS: Final = ("pos", "quat", "vel", "angvel")
QUAT_KEYS: Final = ("w", "x", "y", "z")  # /bodies quaternions; /tf uses Foxglove's x, y, z, w
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
