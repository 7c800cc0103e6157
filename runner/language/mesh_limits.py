"""Bounds on the mesh files a model names, checked before a mesh is read (docs/reliability.md, "Limits").

A mesh is read whole, processed (vertices merged), then turned into a convex hull or kept as triangles in
Python tuples: a binary STL of 327,680 triangles (16 MB, every vertex on its hull) took 3.8 s and 180 MB
more as triangles, 13 s and 280 MB as a hull (measured on the shared machine); a 200 MB STL took 2.7 GB
and over 90 s before these bounds. The file's size is checked from its ``stat``, and its triangle and vertex
counts from the file's own header (binary STL, PLY) or by counting its lines (OBJ, ASCII STL) before
anything is parsed, and once more after loading (any other format). The largest mesh in pybullet_data is a
10 MB OBJ of 124,990 triangles (samurai_monastry.obj).
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

from runner.language.robot_desc import ModelFileError

#: bytes of one mesh file
MAX_MESH_BYTES = 25_000_000
#: triangles (faces) and vertices of one mesh
MAX_MESH_TRIANGLES = 250_000
MAX_MESH_VERTICES = 250_000

_PLY_ELEMENT = re.compile(rb"^element\s+(vertex|face)\s+(\d+)", re.MULTILINE)


def _too_many(kind: str, count: int, limit: int, mesh: Path) -> str | None:
    return f"the mesh {mesh.name} holds {count} {kind}; at most {limit} are read" if count > limit else None


def _counts(path: Path, size: int) -> tuple[int, int] | None:
    """(triangles, vertices) the file says it holds, read without parsing it; None when its format does not
    say (then the counts are checked after loading)."""
    suffix = path.suffix.lower()
    with path.open("rb") as handle:
        head = handle.read(84)
        if suffix == ".stl" and not head.lstrip().startswith(b"solid") and len(head) == 84:
            (triangles,) = struct.unpack("<I", head[80:84])  # binary STL: 80-byte header, then the count
            return triangles, 0  # STL repeats shared vertices: counted once merged, after loading
        if suffix == ".ply":
            header = head + handle.read(4096)
            found = dict(_PLY_ELEMENT.findall(header[: header.find(b"end_header")]))
            return int(found.get(b"face", b"0")), int(found.get(b"vertex", b"0"))
        if suffix in (".obj", ".stl"):  # text: one line per vertex and face (ASCII STL: `facet` per triangle)
            text = head + handle.read(size)
            if suffix == ".stl":
                return text.count(b"facet normal"), 0
            return len(re.findall(rb"(?m)^\s*f\s", text)), len(re.findall(rb"(?m)^\s*v\s", text))
    return None


def check_mesh_file(path: Path, model: Path, line: int, near: str) -> None:
    """Refuse, before reading it, a mesh file larger than MAX_MESH_BYTES or holding more triangles or vertices
    than the limits; located at the model file's line naming the mesh."""
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ModelFileError(model, line, f"cannot read the mesh {path.name}: {exc.strerror}", near=near) from None
    if size > MAX_MESH_BYTES:
        raise ModelFileError(model, line, f"the mesh {path.name} is larger than {MAX_MESH_BYTES} bytes ({size})",
                             near=near)  # fmt: skip
    try:
        counts = _counts(path, size)
    except OSError as exc:
        raise ModelFileError(model, line, f"cannot read the mesh {path.name}: {exc.strerror}", near=near) from None
    if counts is not None:
        check_mesh_counts(counts[0], counts[1], path, model, line, near)


def check_mesh_counts(triangles: int, vertices: int, path: Path, model: Path, line: int, near: str) -> None:
    problem = _too_many("triangles", triangles, MAX_MESH_TRIANGLES, path) or _too_many(
        "vertices", vertices, MAX_MESH_VERTICES, path
    )
    if problem is not None:
        raise ModelFileError(model, line, problem, near=near)
