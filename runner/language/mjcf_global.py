"""MJCF's `<compiler coordinate="global">` (MuJoCo 2.3.3 and older) rewritten in local frames.

In the global dialect every position and orientation in `<worldbody>` is in world coordinates, given or left
at its default (a geom or joint without `pos` is at the world's origin, a joint without `axis` turns about the
world's z): a body's `pos` and orientation, its geoms', sites', cameras' and lights' `pos`, orientation and
`fromto`, its joints' `pos` and `axis`, its `<inertial>` frame, a light's `dir`. MuJoCo 2.3.3 converted
them to frames local to the parent body when it compiled the file; MuJoCo 4 refuses the file. Here each
element's world pose is computed as that compiler read it (orientation from `quat`, `axisangle`, `euler` with
`<compiler angle eulerseq>`, `xyaxes` or `zaxis`) and written back as its `pos`/`quat` (or `fromto`, `axis`,
`dir`) in its parent's frame, full double precision; `coordinate` is then removed.

A body without `pos`: MuJoCo 2.3.3 put its frame at its inertial frame (centre of mass, principal axes);
pybullet's `loadMJCF` at the world's origin, unturned. Here pybullet's (the reference the upgrade is measured
against, tests/backends/test_mjcf_legacy_pybullet.py): the body's geoms, joints and inertia are where both put
them, so the dynamics are the same; only the frame a body's pose is reported in differs.

What the conversion cannot place is refused at its line: a position or orientation in a `<default>` class
(it would hold in every frame), and elements that compose frames of their own (`<include>`, `<frame>`,
`<replicate>`, `<attach>`, `<composite>`, `<flexcomp>`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from runner.language.robot_desc import ModelFileError

_ORIENTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")
_PLACED = {"body", "geom", "site", "camera", "light", "inertial", "joint", "freejoint"}
#: elements the global dialect never had, or whose contents the conversion would not see
_UNCONVERTED = ("include", "frame", "replicate", "attach", "composite", "flexcomp")
_DEFAULTED = ("pos", "fromto", "axis", "dir", *_ORIENTATIONS)


def _numbers(file: Path, element: Any, key: str, count: int) -> np.ndarray:
    text = element.get(key)
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        values = []
    if len(values) < count:
        raise ModelFileError(file, element.sourceline or 0, f"<{element.tag}> {key}=\"{text}\": {count} numbers "
                             "expected (global coordinates)", near=key)  # fmt: skip
    return np.asarray(values[:count], dtype=float)


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    unit = axis / np.linalg.norm(axis)
    half = angle / 2.0
    return _quat_matrix(np.array([math.cos(half), *(math.sin(half) * unit)]))


def _matrix_quat(r: np.ndarray) -> np.ndarray:
    """The unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method, w >= 0)."""
    trace = float(np.trace(r))
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = np.array([0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s])
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 1e-300))
        q = np.zeros(4)
        q[0] = (r[k, j] - r[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + k] = (r[k, i] + r[i, k]) / s
    q = q / np.linalg.norm(q)
    return q if q[0] >= 0.0 else -q


class Compiler:
    """The `<compiler>` settings orientations are read with: angle unit and Euler sequence (MJCF defaults:
    degrees, "xyz")."""

    def __init__(self, root: Any) -> None:
        self.degree, self.eulerseq = True, "xyz"
        for compiler in root.iter("compiler"):
            if compiler.get("angle") is not None:
                self.degree = compiler.get("angle") != "radian"
            if compiler.get("eulerseq") is not None:
                self.eulerseq = compiler.get("eulerseq")

    def angle(self, value: float) -> float:
        return math.radians(value) if self.degree else value

    def rotation(self, file: Path, element: Any) -> np.ndarray:
        """The element's orientation as MuJoCo reads it (identity when it has none)."""
        if element.get("quat") is not None:
            return _quat_matrix(_numbers(file, element, "quat", 4))
        if element.get("axisangle") is not None:
            values = _numbers(file, element, "axisangle", 4)
            return _axis_angle(values[:3], self.angle(float(values[3])))
        if element.get("euler") is not None:
            angles = _numbers(file, element, "euler", 3)
            out = np.eye(3)
            for letter, value in zip(self.eulerseq, angles, strict=True):
                axis = np.eye(3)["xyz".index(letter.lower())]
                turn = _axis_angle(axis, self.angle(float(value)))
                out = out @ turn if letter.islower() else turn @ out  # lowercase: axes that move with the frame
            return out
        if element.get("xyaxes") is not None:
            values = _numbers(file, element, "xyaxes", 6)
            x = values[:3] / np.linalg.norm(values[:3])
            y = values[3:] - x * float(x @ values[3:])
            y = y / np.linalg.norm(y)
            return np.column_stack([x, y, np.cross(x, y)])
        if element.get("zaxis") is not None:
            z = _numbers(file, element, "zaxis", 3)
            z = z / np.linalg.norm(z)
            turn = np.cross([0.0, 0.0, 1.0], z)
            if np.linalg.norm(turn) < 1e-12:
                return np.eye(3) if z[2] > 0 else _axis_angle(np.array([1.0, 0.0, 0.0]), math.pi)
            return _axis_angle(turn, math.atan2(float(np.linalg.norm(turn)), float(z[2])))
        return np.eye(3)


def _text(values: np.ndarray) -> str:
    return " ".join(repr(float(v) + 0.0) for v in values)


def _set_orientation(element: Any, rotation: np.ndarray) -> None:
    for key in _ORIENTATIONS:
        element.attrib.pop(key, None)
    element.set("quat", _text(_matrix_quat(rotation)))


def _refuse_unconvertible(root: Any, file: Path) -> None:
    for element in root.iter(*_UNCONVERTED):
        raise ModelFileError(file, element.sourceline or 0, f"<{element.tag}> in a file with `<compiler "
                             "coordinate=\"global\">`: not converted to local coordinates (MuJoCo 4 reads local "
                             "coordinates only)")  # fmt: skip
    for default in root.iter("default"):
        for element in default:
            if not isinstance(element.tag, str) or element.tag == "default":
                continue
            for key in _DEFAULTED:
                if element.get(key) is not None:
                    raise ModelFileError(file, element.sourceline or 0, f"<default> <{element.tag} {key}>: a "
                                         "default position or orientation in global coordinates is not converted "
                                         "to local ones", near=key)  # fmt: skip


def _convert_child(file: Path, compiler: Compiler, element: Any, origin: np.ndarray, frame: np.ndarray) -> None:
    """A body's geom, site, camera, light, inertial or joint from world coordinates into the body's frame
    (``origin``, ``frame``: the body's world position and rotation)."""
    if element.tag == "freejoint":
        return  # no position or axis: the body's frame
    if element.tag == "joint":
        if element.get("type") != "free":
            axis = _numbers(file, element, "axis", 3) if element.get("axis") is not None else np.array([0.0, 0, 1])
            element.set("axis", _text(frame.T @ axis))
        pos = _numbers(file, element, "pos", 3) if element.get("pos") is not None else np.zeros(3)
        element.set("pos", _text(frame.T @ (pos - origin)))
        return
    if element.get("fromto") is not None:
        ends = _numbers(file, element, "fromto", 6)
        element.set("fromto", _text(np.concatenate([frame.T @ (ends[:3] - origin), frame.T @ (ends[3:] - origin)])))
        return
    pos = _numbers(file, element, "pos", 3) if element.get("pos") is not None else np.zeros(3)
    rotation = compiler.rotation(file, element)
    element.set("pos", _text(frame.T @ (pos - origin)))
    _set_orientation(element, frame.T @ rotation)
    if element.tag == "light":
        direction = _numbers(file, element, "dir", 3) if element.get("dir") is not None else np.array([0.0, 0, -1])
        element.set("dir", _text(frame.T @ direction))


def _convert_body(file: Path, compiler: Compiler, body: Any, origin: np.ndarray, frame: np.ndarray) -> None:
    """``body``'s children (the body itself already local), from world coordinates; its sub-bodies in turn."""
    for child in body:
        if not isinstance(child.tag, str) or child.tag not in _PLACED:
            continue
        if child.tag == "body":
            pos = _numbers(file, child, "pos", 3) if child.get("pos") is not None else np.zeros(3)
            rotation = compiler.rotation(file, child)
            child.set("pos", _text(frame.T @ (pos - origin)))
            _set_orientation(child, frame.T @ rotation)
            _convert_body(file, compiler, child, pos, rotation)
        else:
            _convert_child(file, compiler, child, origin, frame)


def to_local(root: Any, file: Path) -> list[str]:
    """Every `coordinate="global"` of ``root`` (an lxml element, edited in place) removed and the worldbody's
    contents rewritten in local frames; the notes saying so (none when the file is local)."""
    compilers = [c for c in root.iter("compiler") if c.get("coordinate") == "global"]
    if not compilers:
        return []
    _refuse_unconvertible(root, file)
    compiler = Compiler(root)
    for element in root.iter("compiler"):
        element.attrib.pop("coordinate", None)
    for world in root.iter("worldbody"):
        _convert_body(file, compiler, world, np.zeros(3), np.eye(3))
    line = compilers[0].sourceline or 0
    return [f"legacy MJCF: `<compiler coordinate=\"global\">` (line {line}), which MuJoCo dropped in 2.3.3: every "
            "body, geom, site, joint, inertial, camera and light of <worldbody> rewritten in its parent body's "
            "frame, as MuJoCo 2.3.3 converted them (a body without `pos` at the world's origin, as pybullet reads "
            "it)"]  # fmt: skip
