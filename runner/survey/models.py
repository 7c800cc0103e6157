"""The survey's models and the scenario each one runs in (docs/robots.md, "The survey").

A model is a ``.urdf`` (or ``.xml``) file whose root is ``<robot>``, or an ``.xml`` file with a ``<worldbody>``
(MJCF's; an ``<include>``d fragment has none and is no model). Each is run unmodified in a minimal
scenario built in memory:

* a static ground plane at z = 0, gravity -9.81 m/s^2 along z, ``dt`` = 0.002 s (MuJoCo's default
  timestep), the survey's duration, no assertions;
* the model as robot ``model``, raised so that the lowest point of its collision shapes at its start (the
  zero configuration, a joint whose zero is outside its range at its nearest end; planes left out) is
  ``CLEARANCE`` above the ground: a free model falls 1 cm and lands;
* a URDF's root is free, unless the root link has no mass: then it is fixed, as pybullet's ``loadURDF``
  makes a base of mass 0 (whether an author meant a model to be loaded with ``useFixedBase`` is not in the
  file). An MJCF model is as written (its world body is static; a body is free only with a free joint).
"""

from __future__ import annotations

import fnmatch
import hashlib
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from backends.geometry import quat_matrices
from backends.types import ShapeKind
from runner.compile.robot_start import link_motions
from runner.language.robot_desc import ModelDesc, data_root
from runner.language.urdf_rules import shape_points

#: gap between the model's lowest collision point and the ground at the start (m)
CLEARANCE = 0.01
#: the survey's step (s): MuJoCo's default timestep
DT = 0.002
ROBOT = "model"

_ROOT_TAG = re.compile(rb"<\s*([A-Za-z_][\w:.-]*)[\s>/]")


@dataclass(frozen=True)
class ModelFile:
    path: Path  # absolute
    label: str  # as the table shows it: relative to the folder it was found under, with that folder's name
    format: str  # urdf | mjcf


def _root_tag(path: Path) -> str | None:
    """The document element's name, read from the first 64 KiB (comments, declarations and DOCTYPEs skipped)."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(65536)
    except OSError:
        return None
    head = re.sub(rb"<!--.*?-->|<\?.*?\?>|<!DOCTYPE[^>]*>", b"", head, flags=re.S)
    found = _ROOT_TAG.search(head)
    return None if found is None else found.group(1).decode("ascii", "replace")


def _kind(path: Path) -> str | None:
    suffix = path.suffix.lower()
    if suffix == ".urdf":
        return "urdf" if _root_tag(path) == "robot" else None
    if suffix == ".xml":
        tag = _root_tag(path)
        if tag == "robot":
            return "urdf"
        try:
            text = path.read_bytes()
        except OSError:
            return None
        return "mjcf" if tag is not None and b"<worldbody" in text else None  # MJCF's own element
    return None


def resolve_root(text: str) -> Path:
    """A folder or file the survey was given: a path, or `@pybullet_data[/...]`."""
    rooted = data_root(text)
    return (rooted[0] / rooted[1]).resolve() if rooted is not None else Path(text).resolve()


def find_models(paths: Sequence[str], exclude: Sequence[str] = ()) -> list[ModelFile]:
    """Every model under ``paths`` (files are taken as they are; folders searched recursively), in a stable
    order, without those whose label, file name or path under the folder matches a pattern of ``exclude``
    (fnmatch: ``random_urdfs/*``)."""
    found: dict[Path, ModelFile] = {}
    for text in paths:
        root = resolve_root(text)
        shown = text.rstrip("/") if text.startswith("@") else root.name
        files = (
            [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.suffix.lower() in (".urdf", ".xml"))
        )
        for file in files:
            kind = _kind(file)
            if kind is None or file in found:
                continue
            label = shown if file == root else f"{shown}/{file.relative_to(root).as_posix()}"
            names = (label, file.name, file.relative_to(root).as_posix() if file != root else file.name)
            if any(fnmatch.fnmatch(name, pattern) for name in names for pattern in exclude):
                continue
            found[file] = ModelFile(file, label, kind)
    return list(found.values())


def lowest_point(desc: ModelDesc) -> float:
    """The lowest z of the model's collision shapes at its start (the zero configuration, with a joint whose
    zero is outside its range at its nearest end: ``ModelDesc.start``), in the model frame (0 if it has none
    but planes)."""
    motions = link_motions(desc, {j: (q, 0.0) for j, q in desc.start}) if desc.start else {}
    lows = []
    for link in desc.links:
        motion = motions.get(link.name)
        turn = np.eye(3) if motion is None else motion.rot
        at = np.asarray(link.pos, dtype=float) if motion is None else motion.apply(np.asarray(link.pos, dtype=float))
        for placed in link.shapes:
            if placed.shape.kind is ShapeKind.PLANE:
                continue
            points = shape_points(placed)
            if len(points):
                world = points @ (turn @ quat_matrices(link.quat)).T + at
                lows.append(float(world[:, 2].min()))
    return min(lows) if lows else 0.0


def scenario_name(model: ModelFile) -> str:
    """A scenario name (letters, digits, `_.-`) unique to the model's path."""
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", model.label)[-80:].strip("._-") or "model"
    return f"survey.{stem}.{hashlib.sha256(str(model.path).encode()).hexdigest()[:6]}"


def scenario_text(model: ModelFile, lift: float, fixed: bool, duration: float) -> str:
    """The scenario's YAML (the model file relative to the scenario, which sits beside it)."""
    fixed_text = ", fixed: true" if fixed else ""
    return (
        "schema_version: 1\n"
        f"scenario: {scenario_name(model)}\n"
        f"description: {_quoted(model.label + ' unmodified on a ground plane under gravity (robots survey)')}\n"
        f"world: {{gravity: [0, 0, -9.81], dt: {DT}, duration: {duration!r}}}\n"
        "bodies:\n"
        "  ground: {plane: {}, motion: static}\n"
        "robots:\n"
        f"  {ROBOT}: {{{model.format}: {_quoted(model.path.name)}, pos: [0, 0, {lift!r}]{fixed_text}}}\n"
    )


def _quoted(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'
