"""A body of several shapes as one btCompoundShape (``createCollisionShapeArray``), convex hulls included.

``createCollisionShapeArray`` (pybullet.c) takes a GEOM_MESH only as a file name: unlike
``createCollisionShape`` it has no ``vertices`` argument (pybullet 3.2.7: "'vertices' is an invalid keyword
argument"). For an OBJ file, PhysicsServerCommandProcessor's ``processCreateCollisionShapeCommand`` reads
it with Bullet's tinyobjloader (no cache) and adds, per OBJ object, one btConvexHullShape of the vertices
its faces name (``addPoint`` each, then ``optimizeConvexHull``) to the compound at the child's frame, as it
does for vertices given in memory. So each hull goes in as a file whose faces name every vertex.

Precision: tinyobjloader keeps a vertex as ``(float)atof(text)``. The text is Python's shortest round-trip
repr, so ``atof`` gives back the double exactly and the cast rounds it once to the nearest float32: a
coordinate moves by at most 2^-24 of its magnitude, and not at all when it is a float32 already (an STL
mesh's, at scale 1). Bullet then snaps every hull, from a file or from memory alike, to a grid of 1/10216 of
its extent per axis (docs/backends/pybullet.md, "Robots"): 9.8e-5 of the extent against float32's 6.0e-8 of
the magnitude.

The files live only for the one call that reads them (DIRECT mode: the server runs in this process and has
read them when the call returns), in a fresh temporary folder of their own, so concurrent runs never share
a file and nothing is left behind, also on an error. pybullet.c reads the path as ASCII and Bullet copies
it into 1,024-byte buffers (one without a check), so a longer or non-ASCII temporary folder is refused,
naming ``TMPDIR``; ``atof`` follows the C locale, which Python leaves at "C" unless something sets it, so
one whose decimal point is not ``.`` is refused too.
"""

from __future__ import annotations

import locale
import tempfile
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

from ..errors import UnsupportedFeature
from ..geometry import quat_rotate
from ..types import BodySpec, Mesh, PlacedShape, Shape, ShapeKind, Vec3

#: Half size of the box that stands in for a static plane (its top face is the plane).
PLANE_HALF_SIZE = 1000.0
#: MAX_COMPOUND_COLLISION_SHAPES (SharedMemoryCommands.h): the shapes one createCollisionShapeArray holds;
#: b3CreateCollisionShapeAdd* drops any further one without a word [checked: 20 boxes built 16].
MAX_COMPOUND_SHAPES = 16
#: Bullet's path buffers are char[1024] (VISUAL_SHAPE_MAX_PATH_LEN; findResourcePath's sprintf target).
_MAX_PATH = 1000


def xyzw(q: tuple[float, float, float, float]) -> list[float]:
    """(w, x, y, z) -> PyBullet's [x, y, z, w]."""
    return [q[1], q[2], q[3], q[0]]


def mesh_of(shape: Shape) -> Mesh:
    if shape.mesh is None:
        raise UnsupportedFeature(f"Backend `pybullet`: a {shape.kind.value} shape without a mesh.")
    return shape.mesh


def check_compound(spec: BodySpec) -> None:
    """Refuse a compound PyBullet would build short: more than 16 shapes, or a triangle mesh among them."""
    placed = spec.shapes
    if spec.shape.kind is not ShapeKind.COMPOUND or len(placed) < 2:
        return
    if len(placed) > MAX_COMPOUND_SHAPES:
        raise UnsupportedFeature(
            f"Backend `pybullet` cannot build body `{spec.name}`: a compound of {len(placed)} shapes (PyBullet's "
            f"createCollisionShapeArray holds at most {MAX_COMPOUND_SHAPES})."
        )
    if any(s.shape.kind is ShapeKind.TRIMESH for s in placed):  # shape:trimesh is not declared: refused before
        raise UnsupportedFeature(f"Backend `pybullet` cannot build body `{spec.name}`: a triangle mesh in a compound.")


def compound_shape(p: Any, c: int, placed: tuple[PlacedShape, ...], offset: Vec3) -> int:
    """The shapes at their poses in a link frame whose origin is at ``offset`` in the body frame."""
    cols: dict[str, list[Any]] = {k: [] for k in ("type", "half", "radius", "length", "file", "pos", "orn")}
    with ExitStack() as stack:
        hulls = any(s.shape.kind is ShapeKind.CONVEX for s in placed)
        folder = stack.enter_context(_hull_folder()) if hulls else Path()  # the folder only holds hulls
        for index, one in enumerate(placed):
            shape, pos, quat = one.shape, add(offset, one.pos), one.quat
            half, radius, length, file, kind = [0.0] * 3, 0.0, 0.0, "", shape.kind
            if kind is ShapeKind.BOX:
                geom, half = p.GEOM_BOX, [s / 2 for s in shape.size]
            elif kind is ShapeKind.SPHERE:
                geom, radius = p.GEOM_SPHERE, shape.radius
            elif kind in (ShapeKind.CAPSULE, ShapeKind.CYLINDER):
                geom = p.GEOM_CAPSULE if kind is ShapeKind.CAPSULE else p.GEOM_CYLINDER
                radius, length = shape.radius, shape.length
            elif kind is ShapeKind.CONVEX:  # check_compound refused a triangle mesh
                geom, file = p.GEOM_MESH, _write_hull(folder / f"hull-{index:02d}.obj", mesh_of(shape))
            else:  # a plane: the 2 km box of _build._shape
                geom, half = p.GEOM_BOX, [PLANE_HALF_SIZE] * 3
                pos = add(pos, quat_rotate(quat, (0.0, 0.0, -PLANE_HALF_SIZE)))
            for key, value in zip(cols, (geom, half, radius, length, file, list(pos), xyzw(quat)), strict=True):
                cols[key].append(value)
        return int(  # lists, not tuples: pybullet.c reads fileNames and the frames with PyList_GET_ITEM
            p.createCollisionShapeArray(
                shapeTypes=cols["type"],
                halfExtents=cols["half"],
                radii=cols["radius"],
                lengths=cols["length"],
                fileNames=cols["file"],
                meshScales=[[1.0, 1.0, 1.0] for _ in placed],
                collisionFramePositions=cols["pos"],
                collisionFrameOrientations=cols["orn"],
                physicsClientId=c,
            )
        )


def obj_text(mesh: Mesh) -> str:
    """The hull's vertices as OBJ text, with faces that name every vertex: tinyobjloader's hull takes only
    the points its faces name, and their shape does not matter (Bullet rebuilds the hull)."""
    n = len(mesh.vertices)
    lines = ["v " + " ".join(repr(float(x)) for x in v) for v in mesh.vertices]
    lines += [f"f {i + 1} {(i + 1) % n + 1} {(i + 2) % n + 1}" for i in range(0, n, 3)]
    return "\n".join(lines) + "\n"


@contextmanager
def _hull_folder() -> Iterator[Path]:
    """A fresh temporary folder for one compound's hull files, removed on leaving (also on an error)."""
    if locale.localeconv()["decimal_point"] != ".":  # atof would stop at each number's point
        raise UnsupportedFeature(
            "Backend `pybullet` builds a compound's convex hulls from files whose numbers Bullet reads in the "
            "process's C locale, and its LC_NUMERIC does not write a decimal point as `.`."
        )
    with tempfile.TemporaryDirectory(prefix="scenario-pybullet-hulls-") as name:
        probe = str(Path(name) / "hull-00.obj")
        if not probe.isascii() or len(probe.encode()) > _MAX_PATH:
            raise UnsupportedFeature(
                f"Backend `pybullet` builds a compound's convex hulls from files in a temporary folder, and "
                f"`{name}` is not an ASCII path under {_MAX_PATH} bytes as Bullet requires: set TMPDIR to one."
            )
        yield Path(name)


def _write_hull(path: Path, mesh: Mesh) -> str:
    path.write_text(obj_text(mesh), encoding="ascii")
    return str(path)


def add(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])
