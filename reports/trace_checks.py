"""The checks of a trace's metadata as it is read: its format version, the scenario record's JSON values and
their shapes, the names it declares (bounded) and the result's summary, so that what reports read from
them never meets a malformed value; a failed check is a :class:`~reports.trace_model.TraceReadError`.
"""

from __future__ import annotations

from pathlib import Path

from reports import trace_format as tf
from reports.trace_model import TraceReadError, trace_json

__all__ = ["MAX_TRACE_NAMES", "check_format", "check_scenario_json", "check_summary", "record_names"]

#: Bounded before the work: the bodies and joints a trace names (each is a column of every step: 300,000
#: names in a 3.2 MB trace took 13.5 GB)
MAX_TRACE_NAMES = 100_000


def check_format(path: Path, metadata: dict[str, str]) -> None:
    """Refuse a trace of another format version, naming it."""
    version = metadata.get(tf.KEY_TRACE_FORMAT, "")
    if version == str(tf.TRACE_FORMAT_VERSION):
        return
    known = tf.PREVIOUS_FORMATS.get(int(version)) if version.isascii() and version.isdigit() else None
    what = f"trace format {version or '(none)'}" + (f" ({known})" if known else "")
    raise TraceReadError(
        f"{path} is in {what}; this version of physics-scenarios reads trace format {tf.TRACE_FORMAT_VERSION} "
        "only. Run the scenario again to get a trace in the current format."
    )


def record_names(path: Path, metadata: dict[str, str], key: str) -> list[str]:
    """The bodies or joints the scenario record names under ``key``: a JSON list of at most MAX_TRACE_NAMES."""
    try:
        names = trace_json(metadata.get(key, "[]"))
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


def check_scenario_json(path: Path, metadata: dict[str, str]) -> None:
    for key, item in _SCENARIO_JSON.items():
        if key not in metadata:
            continue
        try:
            value = trace_json(metadata[key])
        except ValueError as exc:
            raise TraceReadError(f"{path} is not a physics-scenarios trace: its scenario record's {key!r} is not "
                                 f"JSON ({exc})") from exc  # fmt: skip
        shape = dict if key == tf.KEY_ENGINE_SETTINGS else list
        if not isinstance(value, shape) or (item is not None and not all(isinstance(v, item) for v in value)):
            kind = "an object" if shape is dict else f"a list of {'names' if item is str else 'objects'}"
            raise TraceReadError(f"{path} is not a physics-scenarios trace: its scenario record's {key!r} is not "
                                 f"{kind}")  # fmt: skip


def check_summary(path: Path, metadata: dict[str, dict[str, str]]) -> None:
    """The result record's summary, when there is one, is a JSON object."""
    text = metadata.get(tf.METADATA_RESULT, {}).get(tf.KEY_SUMMARY)
    if not text:
        return
    try:
        summary = trace_json(text)
    except ValueError as exc:
        raise TraceReadError(f"{path} is not a physics-scenarios trace: its summary is not JSON ({exc})") from exc
    if not isinstance(summary, dict):
        raise TraceReadError(f"{path} is not a physics-scenarios trace: its summary is not a JSON object")
