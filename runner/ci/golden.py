"""Golden files for regression checks: the text format, reading, writing, and recording from a trace.

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
_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|\S+')
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


def _untok(raw: str) -> str:
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


# ---- reading -------------------------------------------------------------------------------------------
def read_golden(path: Path) -> Recording:
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise BaselineError(f"no baseline {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise BaselineError(f"cannot read the baseline {path}: {exc}") from None
    return loads(text, str(path))


Rows = dict[str, dict[str, dict[int, list[Any]]]]  # kind -> name -> step -> values


#: at most this many state samples (steps / every + 1) in a golden file: 10^6 rows of 13 numbers per body
MAX_SAMPLES = 1_000_000
#: at most this many steps in the header (a run of a day at dt = 1 ms is 8.64e7)
MAX_STEPS = 10**9


class _Bad(ValueError):
    """A token of a line that cannot be what its place says (``token``: its index in the line)."""

    def __init__(self, message: str, token: int) -> None:
        super().__init__(message)
        self.token = token


def loads(text: str, origin: str = "<golden>") -> Recording:
    """A golden file's recording; a malformed or out-of-range line is :class:`BaselineError` located at its
    ``file:line:column`` and naming its field."""
    rec = Recording(header={})
    rows: Rows = {"body": {}, "joint": {}, "var": {}}
    steps: dict[int, int] = {}  # step -> the line that first sampled it
    where: dict[str, int] = {}  # header key -> its line
    first_lines: dict[str, dict[str, int]] = {kind: {} for kind in rows}  # kind -> name -> its first line
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        found = list(_TOKEN.finditer(line))
        try:
            _parse_line(rec, [m.group() for m in found], rows, steps, number, where)
            if found[0].group() in first_lines and len(found) > 2:
                first_lines[found[0].group()].setdefault(_untok(found[2].group()), number)
        except _Bad as exc:
            column = found[min(exc.token, len(found) - 1)].start() + 1
            raise BaselineError(f"{origin}:{number}:{column}: {exc}") from None
        except (ValueError, KeyError, IndexError, RecursionError, json.JSONDecodeError) as exc:
            raise BaselineError(f"{origin}:{number}: cannot read this line ({exc}): {line[:120]}") from None
    missing = [k for k in ("format", "scenario", "variant", "backend", "dt", "every") if k not in rec.header]
    if missing:
        raise BaselineError(f"{origin}: not a baseline file (no {', '.join(missing)} in its header)")
    if int(rec.header["format"]) != FORMAT_VERSION:
        raise BaselineError(f"{origin}:{where['format']}: format {rec.header['format']}; this runner reads format "
                            f"{FORMAT_VERSION}")  # fmt: skip
    every, last = int(rec.header["every"]), int(rec.header.get("steps", max(steps, default=0)))
    if last // every + 1 > MAX_SAMPLES:
        at = where.get("steps", where["every"])
        raise BaselineError(f"{origin}:{at}: steps {last} sampled every {every}: {last // every + 1} samples, "
                            f"more than the {MAX_SAMPLES} a golden file may hold")  # fmt: skip
    rec.steps = sample_steps(last, every)
    stray = sorted(set(steps) - set(rec.steps))
    if stray:
        raise BaselineError(f"{origin}:{steps[stray[0]]}: a state line at step {stray[0]}, off the grid of every "
                            f"{every} step(s) up to step {last}")  # fmt: skip
    _fill(rec, rows, origin, first_lines)
    return rec


def _number(tokens: list[str], i: int, what: str, *, low: float = -math.inf, nan: bool = False) -> float:
    """Token ``i`` as a finite number >= ``low`` (or NaN where ``nan``)."""
    try:
        value = float(tokens[i])
    except ValueError:
        raise _Bad(f"{what}: expected a number, found {tokens[i]!r}", i) from None
    if math.isnan(value) and nan:
        return value
    if not (math.isfinite(value) and value >= low):
        bound = "" if low == -math.inf else f" >= {low:g}"
        raise _Bad(f"{what}: expected a finite number{bound}, found {tokens[i]}", i)
    return value


def _whole(tokens: list[str], i: int, what: str, low: int, high: int) -> int:
    text = tokens[i]
    if not (text.isascii() and text.isdigit()) or not low <= int(text) <= high:
        raise _Bad(f"{what}: expected a whole number from {low} to {high}, found {text!r}", i)
    return int(text)


def _header(rec: Recording, tokens: list[str]) -> None:
    key = tokens[0]
    if len(tokens) != 2:
        raise _Bad(f"`{key}`: expected one value, found {len(tokens) - 1}", min(len(tokens) - 1, 2))
    if key == "format":
        _whole(tokens, 1, "`format`", 0, 10**6)
    elif key == "every":
        _whole(tokens, 1, "`every` (steps between samples)", 1, MAX_STEPS)
    elif key == "steps":
        _whole(tokens, 1, "`steps`", 0, MAX_STEPS)
    elif key == "dt":
        if not _number(tokens, 1, "`dt`", low=0.0) > 0:
            raise _Bad("`dt`: expected a finite number > 0, found 0", 1)
    elif key == "end_time":
        _number(tokens, 1, "`end_time`", low=0.0)
    rec.header[key] = _untok(tokens[1])


def _parse_line(rec: Recording, tokens: list[str], rows: Rows, steps: dict[int, int], number: int,
                where: dict[str, int]) -> None:  # fmt: skip
    kind = tokens[0]
    if kind == "tolerance":
        if len(tokens) < 3:
            raise _Bad("`tolerance`: expected FIELD atol=NUMBER and/or rtol=NUMBER", len(tokens) - 1)
        keyed: dict[str, float] = {}
        for i, item in enumerate(tokens[2:], 2):
            key, sep, value = item.partition("=")
            if key not in ("atol", "rtol") or not sep:
                raise _Bad(f"unknown tolerance key {key}; expected atol= and rtol=", i)
            try:
                keyed[key] = _number([value], 0, f"`tolerance {tokens[1]} {key}`", low=0.0)
            except _Bad as exc:
                raise _Bad(str(exc), i) from None
        rec.tolerances[tokens[1]] = Tol(keyed.get("atol"), keyed.get("rtol"))
    elif kind == "verdict":
        status, when, name, measured, expected = tokens[1:6]
        if status not in ("pass", "FAIL"):
            raise _Bad(f"verdict status {status!r}; expected pass or FAIL", 1)
        t = None if when == "-" else _number(tokens, 2, "verdict time", low=0.0)
        rec.verdicts.append(VerdictLine(_untok(name), status == "pass", t, _untok(measured), _untok(expected)))
    elif kind in ("event", "sound"):
        entry = (_number(tokens, 1, f"{kind} time", low=0.0), _untok(tokens[2]), _untok(tokens[3]))
        (rec.events if kind == "event" else rec.sounds).append(entry)
    elif kind in rows:
        if "dt" not in rec.header:
            raise _Bad(f"a `{kind}` line before the header's `dt`", 0)
        time = _number(tokens, 1, f"{kind} time", low=0.0)
        ratio = time / float(rec.header["dt"])  # inf for a time over a subnormal dt
        if not ratio <= MAX_STEPS:
            raise _Bad(f"{kind} time: {tokens[1]} s is more than {MAX_STEPS} steps of dt {rec.header['dt']}", 1)
        step = round(ratio)
        steps.setdefault(step, number)
        name = _untok(tokens[2])
        if kind == "body":
            if len(tokens) != 3 + BODY_COLUMNS + len(BODY_FIELDS):
                raise ValueError(f"expected {BODY_COLUMNS} numbers after pos, quat, vel and angvel")
            values: list[Any] = []
            i = 3
            for fld, keys in BODY_FIELDS:
                if tokens[i] != fld:
                    raise _Bad(f"expected `{fld}`, found `{tokens[i]}`", i)
                values += [_number(tokens, i + 1 + j, f"body `{name}` {fld}.{k}") for j, k in enumerate(keys)]
                i += 1 + len(keys)
        elif kind == "joint":
            if len(tokens) != 9 or tokens[3:9:2] != list(JOINT_FIELDS):
                raise ValueError(f"expected {' '.join(JOINT_FIELDS)} with a value each")
            # NaN is a value a joint records (no motor: no motor force)
            values = [_number(tokens, i, f"joint `{name}` {tokens[i - 1]}", nan=True) for i in (4, 6, 8)]
        else:
            values = [json.loads(" ".join(tokens[3:]))]
        rows[kind].setdefault(name, {})[step] = values
    elif kind in HEADER_KEYS:
        _header(rec, tokens)
        where.setdefault(kind, number)
    else:
        raise _Bad(f"unknown line kind `{kind}`", 0)


def _fill(rec: Recording, rows: Rows, origin: str, lines: dict[str, dict[str, int]]) -> None:
    """Rows per sampled step, carrying a value forward where its line was left out."""
    for kind, series in rows.items():
        for name, by_step in series.items():
            if not rec.steps or rec.steps[0] not in by_step:
                first = min(by_step)
                raise BaselineError(f"{origin}:{lines[kind][name]}: {kind} `{name}` has no line at the first sample "
                                    f"(t = 0); its first is at step {first}")  # fmt: skip
            out: list[list[Any]] = []
            current = by_step[rec.steps[0]]
            for k in rec.steps:
                current = by_step.get(k, current)
                out.append(current)
            if kind == "body":
                rec.bodies[name] = np.array(out, dtype=float).reshape(len(rec.steps), BODY_COLUMNS)
            elif kind == "joint":
                rec.joints[name] = np.array(out, dtype=float).reshape(len(rec.steps), len(JOINT_FIELDS))
            else:
                rec.state[name] = [v[0] for v in out]


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
