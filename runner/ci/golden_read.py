"""Reading a golden file (format: :mod:`runner.ci.golden`) into a :class:`~runner.ci.golden.Recording`, every
line checked: a malformed or out-of-range line is a :class:`~runner.ci.golden.BaselineError` located at its
``file:line:column`` and naming its field; the sizes it declares are bounded before arrays are built.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from runner.ci.golden import (
    BODY_COLUMNS,
    BODY_FIELDS,
    FORMAT_VERSION,
    HEADER_KEYS,
    JOINT_FIELDS,
    BaselineError,
    Recording,
    Tol,
    VerdictLine,
    sample_steps,
    untoken,
)

__all__ = ["MAX_SAMPLES", "MAX_STEPS", "loads", "read_golden"]

_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|\S+')


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
                first_lines[found[0].group()].setdefault(untoken(found[2].group()), number)
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
    rec.header[key] = untoken(tokens[1])


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
        rec.verdicts.append(VerdictLine(untoken(name), status == "pass", t, untoken(measured), untoken(expected)))
    elif kind in ("event", "sound"):
        entry = (_number(tokens, 1, f"{kind} time", low=0.0), untoken(tokens[2]), untoken(tokens[3]))
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
        name = untoken(tokens[2])
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
