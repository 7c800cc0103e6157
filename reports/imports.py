"""How each engine imported a scenario's robots (``Backend.imported_model``), compared across engines.

An *engine read* is the plain data one worker sends back (runner.exec.imports): ``backend``, ``status``
(:data:`READ`, :data:`NOT_REPORTED`, :data:`REFUSED`, :data:`FAILED`), ``eps`` (the machine epsilon of the
engine's float format), ``version``, and for a read its ``bodies`` (name -> mass, principal inertia, COM in the
body frame, collision shapes, ``reach``: how far the body's COM is from the world origin) and ``joints`` (name
-> kind, world axis, stops, and ``[engine, runner]`` pairs for damping, friction loss, effort and velocity:
what the engine holds itself, what the runner adds on that engine). :func:`compare` turns the reads into one
:class:`Table` per quantity, each row flagged where engines differ by more than :func:`tolerance`.

What is compared is what each engine will simulate: damping is the engine's own plus the runner's motor's
(``0.5 engine`` on DART, ``0.5 runner`` where the runner's motor carries it, ``0`` where a servo drives the
joint and the engine has none); effort and velocity the tighter of the engine's own limit and the runner's
cap.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from backends.types import ImportedModel

__all__ = ["FAILED", "IMPORTS_NAME", "NOT_REPORTED", "READ", "REFUSED", "Cell", "Row", "Table", "compare",
           "model_data", "sections_beside", "tolerance", "write_imports"]

READ, NOT_REPORTED, REFUSED, FAILED = "read", "not reported", "refused", "failed"
#: roundings a read value carries in the engine's format, relative to its scale: stored in the format (eps/2)
#: and, for a vector or a position, passed through two rotations kept in that format (into the body's frame at
#: build, back to the world when read, as ODE's hinge axis is); a rotation matrix from a rounded unit quaternion
#: has entries off by up to about eps, so each rotation moves a component of a unit vector by up to 3 eps:
#: 2 x 3 eps + 2 x eps/2 = 7 eps, rounded up to 8
ROUNDINGS = 8.0
DYNAMICS = ("damping", "frictionloss", "effort", "velocity")


#: decimal digits a float32 holds (24 bits: 7.2): a file written with fewer is stated by every engine's format
#: as finely as it is written, so its precision is taken as no coarser than this
FLOAT32_DIGITS = 7


def tolerance(eps_a: float, eps_b: float, digits: int) -> float:
    """Relative tolerance between two engines' reads of one value, from their float formats and the file's own
    precision: :data:`ROUNDINGS` times the coarser format's epsilon, or half a unit in the last place of the
    file's most precise number (``digits`` significant digits, at least :data:`FLOAT32_DIGITS`), whichever is
    larger. A file written with 12 digits (kuka's pi/2 as 1.57079632679) states nothing more finely than 5e-12,
    so an engine that carried a value at the file's precision differs from one that derived it in float64 by
    that much, which is no difference of the import."""
    return max(ROUNDINGS * max(eps_a, eps_b), 0.5 * 10.0 ** (1 - max(digits, FLOAT32_DIGITS)))


def model_data(model: ImportedModel, runner: dict[str, dict[str, float | None]],
               reach: dict[str, float]) -> dict[str, Any]:  # fmt: skip
    """An :class:`ImportedModel` as the read's plain data (``runner``: per joint what the runner adds)."""
    bodies = {
        b.name: {"mass": b.mass, "inertia": list(b.inertia), "com": list(b.com), "shapes": b.shapes,
                 "reach": reach.get(b.name, 0.0)}  # fmt: skip
        for b in model.bodies
    }
    joints = {}
    for j in model.joints:
        extra = runner.get(j.name, {})
        joints[j.name] = {
            "kind": j.kind.value, "axis": None if j.axis is None else list(j.axis), "lo": j.lo, "hi": j.hi,
            **{k: [getattr(j, k), extra.get(k)] for k in DYNAMICS},
        }  # fmt: skip
    return {"bodies": bodies, "joints": joints, "notes": list(model.notes)}


@dataclass
class Cell:
    text: str
    flagged: bool = False


@dataclass
class Row:
    name: str
    cells: dict[str, Cell]  # backend -> its cell (engines that did not report are absent)
    agree: bool = True

    def agreed(self) -> str:
        """The value every engine shows (for a row that agrees)."""
        return next(iter(self.cells.values())).text if self.cells else "–"


@dataclass
class Table:
    title: str
    unit: str
    rows: list[Row] = field(default_factory=list)

    @property
    def differences(self) -> int:
        return sum(not r.agree for r in self.rows)


@dataclass(frozen=True)
class _Quantity:
    title: str
    unit: str
    part: str  # bodies | joints
    key: str


_QUANTITIES = (
    _Quantity("mass", "kg", "bodies", "mass"),
    _Quantity("principal inertia about the COM", "kg m²", "bodies", "inertia"),
    _Quantity("COM in the link frame", "m", "bodies", "com"),
    _Quantity("collision shapes", "count", "bodies", "shapes"),
    _Quantity("joint kind", "", "joints", "kind"),
    _Quantity("joint axis (world)", "unit vector", "joints", "axis"),
    _Quantity("joint limits", "rad or m, from the start", "joints", "limits"),
    _Quantity("damping", "N m s/rad or N s/m", "joints", "damping"),
    _Quantity("friction loss", "N m or N", "joints", "frictionloss"),
    _Quantity("effort limit", "N m or N", "joints", "effort"),
    _Quantity("velocity limit", "rad/s or m/s", "joints", "velocity"),
)


def _num(v: float | None, precise: bool = False, floor: float = 0.0) -> str:
    """A value: 9 significant digits where engines differ (``precise``), else 6; 0 at or below ``floor`` (the
    tolerance of a row that agrees: rounding noise, not a value)."""
    if v is None:
        return "none"
    if abs(v) <= floor:
        return "0"
    return f"{v:.9g}" if precise else f"{v:.6g}"


def _vec(v: list[float] | None, precise: bool = False, floor: float = 0.0) -> str:
    return "none" if v is None else "(" + ", ".join(_num(x, precise, floor) for x in v) + ")"


def _effective(key: str, pair: list[float | None]) -> float | None:
    engine, runner = pair
    if key in ("damping", "frictionloss"):
        return (engine or 0.0) + (runner or 0.0)
    limits = [v for v in (engine, runner) if v is not None]  # the tighter one acts; None: no limit
    return min(limits) if limits else None


def _source(key: str, pair: list[float | None], precise: bool) -> str:
    engine, runner = pair
    if key in ("damping", "frictionloss"):
        parts = [f"{_num(v, precise)} {who}" for v, who in ((engine, "engine"), (runner, "runner")) if v]
        return " + ".join(parts) or "0"
    value = _effective(key, pair)
    if value is None:
        return "none"
    return f"{_num(value, precise)} {'engine' if engine is not None and engine == value else 'runner'}"


def _close(a: Any, b: Any, scale: float, rel: float) -> bool:
    """Whether two values agree: numbers (alone or in lists) within ``rel * scale``, anything else equal; a
    scale of 0 (a count, a kind) asks for equality."""
    xs = a if isinstance(a, list) else [a]
    ys = b if isinstance(b, list) else [b]
    if len(xs) != len(ys):
        return False
    for x, y in zip(xs, ys, strict=True):
        if x == y:
            continue
        if not (_number(x) and _number(y) and math.isfinite(x) and math.isfinite(y)):
            return False
        if abs(x - y) > rel * scale:
            return False
    return True


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _value(q: _Quantity, entry: dict[str, Any]) -> tuple[Any, float]:
    """(value compared, scale its rounding is relative to)."""
    if q.key == "shapes" or q.key == "kind":
        return entry[q.key], 0.0
    if q.key == "mass":
        return entry["mass"], abs(entry["mass"])
    if q.key == "inertia":
        return entry["inertia"], max(abs(x) for x in entry["inertia"])
    if q.key == "com":
        return entry["com"], entry.get("reach", 0.0) + max(abs(x) for x in entry["com"])
    if q.key == "axis":
        return entry["axis"], 1.0
    if q.key == "limits":
        sides = [entry["lo"], entry["hi"]]
        return sides, max([abs(s) for s in sides if s is not None] + [0.0])
    value = _effective(q.key, entry[q.key])
    return value, abs(value) if value is not None else 0.0


def _text(q: _Quantity, entry: dict[str, Any], precise: bool, floor: float = 0.0) -> str:
    if q.key in ("shapes", "kind"):
        return str(entry[q.key])
    if q.key == "mass":
        return _num(entry["mass"], precise, floor)
    if q.key in ("inertia", "com", "axis"):
        return _vec(entry[q.key], precise, floor)
    if q.key == "limits":
        return f"{_num(entry['lo'], precise, floor)} .. {_num(entry['hi'], precise, floor)}"
    return _source(q.key, entry[q.key], precise)


def _groups(values: dict[str, tuple[Any, float]], eps: dict[str, float], digits: int) -> list[list[str]]:
    """Engines in groups that agree with the group's first engine, largest group first (ties: the first)."""
    groups: list[list[str]] = []
    for backend, (value, scale) in values.items():
        for group in groups:
            first = group[0]
            other, other_scale = values[first]
            if _close(value, other, max(scale, other_scale), tolerance(eps[backend], eps[first], digits)):
                group.append(backend)
                break
        else:
            groups.append([backend])
    return sorted(groups, key=lambda g: -len(g))


def compare(reads: list[dict[str, Any]], digits: int) -> list[Table]:
    """One table per quantity; a row per link (body) or joint that some engine reported; in a row that does
    not agree, the engines outside the largest agreeing group are flagged."""
    done = [r for r in reads if r.get("status") == READ]
    eps = {r["backend"]: float(r["eps"]) for r in done}
    tables = []
    for q in _QUANTITIES:
        table = Table(q.title, q.unit)
        names = list(dict.fromkeys(n for r in done for n in r[q.part]))
        for name in names:
            have = {r["backend"]: r[q.part][name] for r in done if name in r[q.part]}
            values = {b: _value(q, e) for b, e in have.items()}
            groups = _groups(values, eps, digits)
            agree = len(groups) <= 1 and len(have) == len(done)
            flagged = set() if agree else {b for g in groups[1:] for b in g} | (set(eps) - set(have))
            coarsest = max(eps[b] for b in have) if have else 0.0
            scale = max([sc for _, sc in values.values()] + [0.0])
            floor = tolerance(coarsest, coarsest, digits) * scale if agree else 0.0
            cells = {b: Cell(_text(q, e, not agree, floor), b in flagged) for b, e in have.items()}
            table.rows.append(Row(name, cells, agree))
        tables.append(table)
    return tables


# ---- the file beside the traces ------------------------------------------------------------------

#: written by `scenario compare` beside the traces, read by every report built from that folder
IMPORTS_NAME = "imports.json"
IMPORTS_FORMAT = "physics-scenarios imports 1"


def imports_path(traces: Path) -> Path:
    return traces / IMPORTS_NAME


def is_own_imports(path: Path) -> bool:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and data.get("format") == IMPORTS_FORMAT


def write_imports(traces: Path, sections: list[dict[str, Any]]) -> Path:
    """The sections as ``traces/imports.json`` (the caller checked that a file there is its own)."""
    from reports.report_files import write_file

    path = imports_path(traces)
    traces.mkdir(parents=True, exist_ok=True)
    write_file(path, json.dumps({"format": IMPORTS_FORMAT, "sections": sections}, allow_nan=False,
                                ensure_ascii=False, sort_keys=True) + "\n")  # fmt: skip
    return path


def sections_beside(paths: list[Path], cases: set[tuple[str, str]]) -> list[dict[str, Any]]:
    """The import sections of ``cases`` ((scenario, variant)) kept in ``imports.json`` beside ``paths``
    (traces or their folders), first found first."""
    out: dict[tuple[str, str], dict[str, Any]] = {}
    for p in paths:
        path = imports_path(p if p.is_dir() else p.parent)
        if not is_own_imports(path):
            continue
        for section in json.loads(path.read_text())["sections"]:
            key = (section["scenario"], section["variant"])
            if key in cases:
                out.setdefault(key, section)
    return list(out.values())
