"""The numbers and names of a URDF or MJCF file, held to the scenario language's own rules (issue 31).

Every number that places, sizes or weighs something (origins, rotations, axes, sizes, radii, lengths, masses,
inertias, mesh scales) must be finite and within +-``MAX_MAGNITUDE`` (the scenario's bound, SI units); the
sizes, radii and lengths of collision shapes positive, masses not negative, a moving joint's axis not zero;
NaN is refused wherever a number is written (joint limits, dynamics). Link and joint (MJCF: body and joint)
names are unique and not empty. Each problem is a :class:`ModelFileError` at the element's line, its column at
the attribute, naming the element and the field: a file that passes loads into a world every engine can be
built from (before, NaN, inf and 1e300 passed `validate` and then aborted ODE, failed at t = 0 or passed
silently; a duplicate link name was accepted by `validate` and crashed `run`, exit 70).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from runner.language.model_base import MAX_MAGNITUDE
from runner.language.robot_desc import ModelFileError

#: (element, attribute) -> the rule for its numbers: "any" (finite, bounded), "positive", "mass" (>= 0)
URDF_FIELDS: dict[tuple[str, str], str] = {
    ("origin", "xyz"): "any",
    ("origin", "rpy"): "any",
    ("axis", "xyz"): "any",
    ("box", "size"): "positive",
    ("sphere", "radius"): "positive",
    ("cylinder", "radius"): "positive",
    ("cylinder", "length"): "positive",
    ("capsule", "radius"): "positive",
    ("capsule", "length"): "positive",
    ("mesh", "scale"): "nonzero",
    ("mass", "value"): "mass",
    **{("inertia", k): "any" for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")},
}
#: how many numbers a URDF attribute holds (default 1); pybullet reads the first 3 of more (microtaur's
#: `rpy="-3.14159 1.57079 0 0"`); a mesh scale is 1 (every axis), or 3 and more
URDF_COUNTS: dict[tuple[str, str], str] = {
    ("origin", "xyz"): "3",
    ("origin", "rpy"): "3",
    ("axis", "xyz"): "3",
    ("box", "size"): "3",
    ("mesh", "scale"): "1 or 3",
}
_OPTENV = re.compile(r"\$\(optenv\s+(\S+)\s*([^)]*)\)")
#: MJCF attributes (any element) that place, size or weigh something
MJCF_FIELDS: dict[str, str] = {
    "pos": "any",
    "quat": "any",
    "euler": "any",
    "axisangle": "any",
    "xyaxes": "any",
    "zaxis": "any",
    "fromto": "any",
    "axis": "any",
    "size": "any",
    "mass": "mass",
    "diaginertia": "mass",
    "fullinertia": "any",
    "scale": "nonzero",
    "density": "any",
}
_MOVING_URDF = {"revolute", "continuous", "prismatic"}
_ITEM = re.compile(r"[^\s,]+")
_LEADING = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _values(text: str) -> list[float] | None:
    """The numbers of an attribute as the loaders read them (each item's leading number, as strtod does;
    `nan`, `inf` as Python reads them); None when an item is not a number at all (left to the loader)."""
    out = []
    for item in _ITEM.findall(text):
        try:
            out.append(float(item))
            continue
        except ValueError:
            pass
        found = _LEADING.match(item)
        if found is None:
            return None
        out.append(float(found.group(0)))
    return out


def _where(element: Any) -> str:
    """`<box>` of link `base`: the element and the named element it belongs to."""
    owner = element
    while owner is not None and not owner.get("name"):
        owner = owner.getparent()
    named = f" of {owner.tag} `{owner.get('name')}`" if owner is not None and owner is not element else ""
    return f"<{element.tag}>{named}"


def check_number(value: float, rule: str) -> str | None:
    """What is wrong with ``value`` under ``rule`` (None: nothing)."""
    if math.isnan(value):
        return "is NaN"
    if not math.isfinite(value) or abs(value) > MAX_MAGNITUDE:
        return f"is beyond +-{MAX_MAGNITUDE:g} (SI units)"
    if rule == "positive" and value <= 0:
        return "must be positive"
    if rule == "mass" and value < 0:
        return "must not be negative"
    if rule == "nonzero" and value == 0:
        return "must not be zero"
    return None


def _text(element: Any, key: str) -> str | None:
    """The attribute's value as the loader reads it: xacro's `$(optenv NAME default)` (husky.urdf) expanded."""
    import os

    text = element.get(key)
    if text is None or "$(optenv" not in text:
        return text
    return _OPTENV.sub(lambda m: os.environ.get(m.group(1), m.group(2)), text)


def _check_attribute(file: Path, element: Any, key: str, rule: str) -> None:
    text = _text(element, key)
    if text is None:
        return
    values = _values(text)
    if values is None:
        return
    for value in values:
        problem = check_number(value, rule)
        if problem is not None:
            raise ModelFileError(
                file, element.sourceline or 0, f"{_where(element)}: `{key}` {text.strip()!r}: {value!r} {problem}",
                near=f"{key}=",
            )  # fmt: skip


def check_urdf_numbers(tree: Any, file: Path) -> None:
    """Every URDF number that places, sizes or weighs something (``URDF_FIELDS``), NaN anywhere a number is
    written, and a moving joint's axis not zero."""
    for element in tree.getroot().iter():
        if not isinstance(element.tag, str):
            continue
        for key in element.attrib:
            rule = URDF_FIELDS.get((element.tag, key))
            if rule is not None and _in_visual(element):
                rule = "any"  # drawn, never simulated: laikago's toes draw a sphere of radius 0
            if rule is not None:
                _check_count(file, element, key, URDF_COUNTS.get((element.tag, key), "1"))
                _check_attribute(file, element, key, rule)
            else:
                _no_nan(file, element, key)
    for joint in tree.getroot().iterfind("joint"):
        axis = joint.find("axis")
        values = _values(axis.get("xyz", "")) if axis is not None else None
        if joint.get("type") in _MOVING_URDF and values is not None and not any(values):
            raise ModelFileError(
                file, axis.sourceline or 0, f"joint `{joint.get('name')}`: `axis` {axis.get('xyz')!r} is zero; a "
                "moving joint needs a direction", near="xyz=",
            )  # fmt: skip


def _check_count(file: Path, element: Any, key: str, count: str) -> None:
    """The attribute holds numbers, as many as ``count`` says ("3", "1", "1 or 3": 1, or 3 and more)."""
    text = _text(element, key) or ""
    values = _values(text)
    found = -1 if values is None else len(values)
    fits = found == 1 or found >= 3 if count == "1 or 3" else found >= 3 if count == "3" else found == 1
    if not fits:
        what = "number" if count == "1" else "numbers"
        if count == "1 or 3":
            what += " (a mesh scale: one for every axis, or x y z)"
        raise ModelFileError(
            file, element.sourceline or 0, f"{_where(element)}: `{key}` {text.strip()!r}: expected {count} {what}",
            near=f"{key}=",
        )  # fmt: skip


def _in_visual(element: Any) -> bool:
    geometry = element.getparent()
    owner = geometry.getparent() if geometry is not None else None
    return owner is not None and owner.tag == "visual"


def check_mjcf_numbers(tree: Any, file: Path) -> None:
    """Every MJCF number that places, sizes or weighs something (``MJCF_FIELDS``), and NaN anywhere."""
    for element in tree.getroot().iter():
        if not isinstance(element.tag, str):
            continue
        for key in element.attrib:
            rule = MJCF_FIELDS.get(key)
            if rule is not None:
                _check_attribute(file, element, key, rule)
            else:
                _no_nan(file, element, key)


def _no_nan(file: Path, element: Any, key: str) -> None:
    text = element.get(key) or ""
    if "nan" not in text.lower():
        return
    values = _values(text)
    if values is not None and any(math.isnan(v) for v in values):
        raise ModelFileError(file, element.sourceline or 0, f"{_where(element)}: `{key}` {text.strip()!r} is NaN",
                             near=f"{key}=")  # fmt: skip


def check_vertices(vertices: np.ndarray, file: Path, line: int, mesh: str) -> None:
    """A mesh's vertices (scaled) finite and within +-MAX_MAGNITUDE."""
    v = np.asarray(vertices, dtype=float)
    if not np.all(np.isfinite(v)):
        raise ModelFileError(file, line, f"the mesh {mesh} has a vertex that is not finite (NaN or inf)", near=mesh)
    if v.size and float(np.abs(v).max()) > MAX_MAGNITUDE:
        raise ModelFileError(file, line, f"the mesh {mesh} has a vertex beyond +-{MAX_MAGNITUDE:g} m", near=mesh)
