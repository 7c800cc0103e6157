"""Golden files for regression checks: the text format, its types, writing, and recording from a trace.

One file per scenario x variant x backend, ``<scenario>__<variant>__<backend>.golden``, made to be read and
diffed in review. Line-oriented; the first token says what a line is::

    format 1                                  header: `key value` (scenario, variant, backend, engine, ...)
    every 2                                   a state sample every 2 steps (and at the last step)
    tolerance pos atol=1e-06 rtol=1e-06       per field, or per `name.field`; `scenario baseline` keeps them
    verdict pass 0.04 kick "2.57059" "2.5706 ± 0.001"    status, time, name, measured, expected
    event 0.96 box-into-door collision-in     time, name, source (in order)
    sound 1.2 thud start                      time, name, action (in order)
    body 0.08 box pos X Y Z quat W X Y Z vel X Y Z angvel X Y Z
    joint 0.08 slider position P velocity V motor_force F
    var 0.08 door_open true                   a state variable (JSON value)

A ``body``/``joint``/``var`` line identical to the same name's previous line is left out (the value holds).
Numbers have 9 significant digits; a token with spaces or quotes is a JSON string.

Reading (and checking) a golden file: :mod:`runner.ci.golden_read`; comparing a run with one:
:mod:`runner.ci.golden_compare`.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runner.errors import ScenarioError

FORMAT_VERSION = 1
SUFFIX = ".golden"
DEFAULT_PERIOD = 0.1  # seconds between state samples, rounded to whole steps
DIGITS = 9
BODY_FIELDS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("pos", ("x", "y", "z")),
    ("quat", ("w", "x", "y", "z")),
    ("vel", ("x", "y", "z")),
    ("angvel", ("x", "y", "z")),
)
BODY_COLUMNS = 13
JOINT_FIELDS = ("position", "velocity", "motor_force")
HEADER_KEYS = (
    "format", "scenario", "variant", "backend", "engine", "tool", "scenario_file", "scenario_sha256",
    "dt", "steps", "end_time", "status", "every",
)  # fmt: skip
_BARE = re.compile(r'[^\s"#]+')


class BaselineError(ScenarioError):
    """A golden file is missing or malformed (bad input, exit 2)."""


@dataclass(frozen=True)
class Tol:
    """An absolute and a relative tolerance: |got - expected| <= atol + rtol * |expected|. None: not set here."""

    atol: float | None = None
    rtol: float | None = None

    def text(self) -> str:
        parts = [f"{k}={_num(v)}" for k, v in (("atol", self.atol), ("rtol", self.rtol)) if v is not None]
        return " ".join(parts)


#: Built-in tolerances: far below anything a scenario asserts, above the file's 9-digit rounding. Fields:
#: body pos/quat/vel/angvel, joint position/velocity/motor_force, `state` (numeric variables), `event` (times of
#: events and sounds); `default` for the rest.
DEFAULT_TOLERANCES: dict[str, Tol] = {
    "default": Tol(1e-6, 1e-6),
    "vel": Tol(1e-5, 1e-6),
    "angvel": Tol(1e-5, 1e-6),
    "velocity": Tol(1e-5, 1e-6),
    "motor_force": Tol(1e-4, 1e-6),
    "state": Tol(1e-9, 1e-9),
    "event": Tol(1e-6, 0.0),
}


class Tolerances:
    """Layers of per-field tolerances, most important first (command line, golden file, built-in).

    ``lookup(name, field)`` takes, for atol and rtol separately, the first layer that sets ``name.field``,
    ``field`` or ``default`` (in that order within a layer)."""

    def __init__(self, *layers: dict[str, Tol]) -> None:
        self.layers = [*layers, DEFAULT_TOLERANCES]

    def lookup(self, name: str, fld: str) -> tuple[float, float]:
        atol = rtol = None
        for layer in self.layers:
            for key in (f"{name}.{fld}", fld, "default"):
                tol = layer.get(key)
                if tol is None:
                    continue
                atol = tol.atol if atol is None else atol
                rtol = tol.rtol if rtol is None else rtol
            if atol is not None and rtol is not None:
                break
        return float(atol or 0.0), float(rtol or 0.0)


@dataclass
class VerdictLine:
    name: str
    passed: bool
    time: float | None
    measured: str
    expected: str


@dataclass
class Recording:
    """What a golden file holds, as arrays (rows: the sampled steps)."""

    header: dict[str, str]
    tolerances: dict[str, Tol] = field(default_factory=dict)
    verdicts: list[VerdictLine] = field(default_factory=list)
    events: list[tuple[float, str, str]] = field(default_factory=list)
    sounds: list[tuple[float, str, str]] = field(default_factory=list)
    steps: list[int] = field(default_factory=list)
    bodies: dict[str, np.ndarray] = field(default_factory=dict)  # (S, 13): pos, quat (w x y z), vel, angvel
    joints: dict[str, np.ndarray] = field(default_factory=dict)  # (S, 3): position, velocity, motor_force
    state: dict[str, list[Any]] = field(default_factory=dict)  # S values each

    @property
    def dt(self) -> float:
        return float(self.header["dt"])

    @property
    def times(self) -> np.ndarray:
        return np.array([quantize(k * self.dt) for k in self.steps])

    def label(self) -> str:
        return f"{self.header.get('scenario')} · {self.header.get('variant')} · {self.header.get('backend')}"


def quantize(x: float) -> float:
    """The value as the file stores it (9 significant digits), so that a run compares with a golden exactly."""
    return float(_num(x))


def _num(x: float) -> str:
    if isinstance(x, float) and math.isnan(x):
        return "nan"
    text = f"{float(x):.{DIGITS}g}"
    return "0" if text == "-0" else text


def _tok(text: str) -> str:
    return text if _BARE.fullmatch(text) else json.dumps(text, ensure_ascii=False)


def untoken(raw: str) -> str:
    """A token as the text it stands for (a JSON string unquoted)."""
    return str(json.loads(raw)) if raw.startswith('"') else raw


def golden_name(scenario: str, variant: str, backend: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{scenario}__{variant}__{backend}") + SUFFIX


def sample_steps(last: int, every: int) -> list[int]:
    """The sampled steps: every ``every``-th from 0, and the last one."""
    grid = list(range(0, last + 1, every))
    return grid if grid[-1] == last else [*grid, last]


def sample_every(dt: float, period: float | None) -> int:
    """Steps between state samples for a period in seconds (0: every step)."""
    period = DEFAULT_PERIOD if period is None else period
    return max(1, round(period / dt)) if period > 0 else 1


# ---- writing -------------------------------------------------------------------------------------------
def dumps(rec: Recording) -> str:
    h = rec.header
    every = int(h["every"])
    lines = [
        "# physics-scenarios baseline: `scenario check` compares a run with this file; `scenario baseline`",
        "# rewrites it and keeps the tolerance lines. SI units; quaternions w x y z; a body, joint or var line",
        "# equal to the same name's previous one is left out.",
    ]
    lines += [f"{key} {_tok(str(h[key]))}" for key in HEADER_KEYS if key in h]
    lines.append(f"# every: a state sample every {every} step(s) = {_num(every * rec.dt)} s, and at the last step")
    lines += [f"tolerance {key} {tol.text()}" for key, tol in sorted(rec.tolerances.items()) if tol.text()]
    for v in rec.verdicts:
        when = "-" if v.time is None or not math.isfinite(v.time) else _num(v.time)
        status = "pass" if v.passed else "FAIL"
        lines.append(f"verdict {status} {when} {_tok(v.name)} {_tok(v.measured)} {_tok(v.expected)}")
    lines += [f"event {_num(t)} {_tok(n)} {_tok(s)}" for t, n, s in rec.events]
    lines += [f"sound {_num(t)} {_tok(n)} {_tok(a)}" for t, n, a in rec.sounds]
    last: dict[str, str] = {}
    for row, k in enumerate(rec.steps):
        t = _num(k * rec.dt)
        for name, arr in rec.bodies.items():
            values = arr[row]
            text, i = "", 0
            for fld, keys in BODY_FIELDS:
                text += f" {fld} " + " ".join(_num(v) for v in values[i : i + len(keys)])
                i += len(keys)
            _emit(lines, last, f"body {_tok(name)}", t, text)
        for name, arr in rec.joints.items():
            text = "".join(f" {fld} {_num(v)}" for fld, v in zip(JOINT_FIELDS, arr[row], strict=True))
            _emit(lines, last, f"joint {_tok(name)}", t, text)
        for name, values in rec.state.items():
            _emit(lines, last, f"var {_tok(name)}", t, " " + json.dumps(values[row], ensure_ascii=False))
    return "\n".join(lines) + "\n"


def _emit(lines: list[str], last: dict[str, str], key: str, t: str, text: str) -> None:
    if last.get(key) != text:
        kind, _, name = key.partition(" ")
        lines.append(f"{kind} {t} {name}{text}")
        last[key] = text


def write_golden(path: Path, rec: Recording) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    tmp.write_text(dumps(rec), encoding="utf-8")
    tmp.replace(path)


# ---- recording from a trace -------------------------------------------------------------------------------
def record_from_trace(trace: Any, every: int, tolerances: dict[str, Tol] | None = None) -> Recording:
    """A golden recording of a trace (:class:`reports.trace_reader.Trace`), sampled every ``every`` steps."""
    meta = trace.scenario
    dt = float(meta["dt"])
    result = trace.result
    all_steps = np.rint(np.asarray(trace.times) / dt).astype(int)
    if not len(all_steps) or list(all_steps) != list(range(len(all_steps))):
        raise BaselineError(f"{trace.path}: the trace does not hold one state per step from t = 0")
    keep = sample_steps(len(all_steps) - 1, every)
    header = {
        "format": str(FORMAT_VERSION),
        "scenario": meta["name"],
        "variant": meta["variant"],
        "backend": meta["backend"],
        "engine": meta.get("backend_version", "unknown"),
        "tool": meta.get("tool_version", "unknown"),
        "scenario_file": meta.get("scenario_path", ""),
        "scenario_sha256": meta.get("scenario_sha256", ""),
        "dt": _num(dt),
        "steps": str(len(all_steps) - 1),
        "end_time": _num(float(result.get("end_time", trace.times[-1] if len(trace.times) else 0.0))),
        "status": trace.status,
        "every": str(every),
    }
    rec = Recording(header=header, tolerances=dict(tolerances or {}))
    rec.steps = list(keep)
    q = np.vectorize(quantize, otypes=[float])
    for name, s in trace.bodies.items():
        rec.bodies[name] = q(np.hstack([s.pos, s.quat, s.vel, s.angvel])[keep]).reshape(len(keep), BODY_COLUMNS)
    joint_rows = _rows_at(trace.joint_times, dt, rec.steps) if trace.joints else []
    for name, s in trace.joints.items():
        arr = np.column_stack([s.position, s.velocity, s.motor_force])
        rec.joints[name] = q(arr[joint_rows]).reshape(len(keep), len(JOINT_FIELDS))
    state_rows = _rows_at(trace.state_times, dt, rec.steps) if trace.state else []
    for name, values in trace.state.items():
        rec.state[name] = [_state_value(values[i]) for i in state_rows]
    for v in trace.verdicts:
        d = v.data
        t = d.get("time")
        rec.verdicts.append(
            VerdictLine(v.name, bool(v.passed), None if t is None else float(t), str(d.get("measured", "")),
                        str(d.get("expected", "")))
        )  # fmt: skip
    rec.events = [(quantize(e.t), e.name, e.source) for e in trace.events]
    rec.sounds = [(quantize(s.t), s.name, s.action) for s in trace.sounds]
    return rec


def _rows_at(times: Any, dt: float, steps: list[int]) -> list[int]:
    index = {int(k): i for i, k in enumerate(np.rint(np.asarray(times) / dt).astype(int))}
    missing = [k for k in steps if k not in index]
    if missing:
        raise BaselineError(f"the trace has no joint or state record at step {missing[0]}")
    return [index[k] for k in steps]


def _state_value(value: Any) -> Any:
    value = value.item() if isinstance(value, np.generic) else value
    return quantize(value) if isinstance(value, float) else value
