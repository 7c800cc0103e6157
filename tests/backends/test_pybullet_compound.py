"""PyBullet compounds with convex hulls among their shapes (backends/pybullet/_compound.py).

``createCollisionShapeArray`` takes a hull only as a file, so each goes in as an OBJ file of its vertices.
What the built hull may differ by, derived from Bullet's code (docs/backends/pybullet.md, "Robots"):
tinyobjloader rounds each coordinate to float32 (at most 2^-24 of its magnitude), then Bullet's
``optimizeConvexHull`` (btConvexHullComputer, for hulls from memory as well) puts the points on an integer
grid of 1/10216 of the hull's extent per axis about its bounding box's centre, truncating toward the centre:
each kept vertex is a given one moved by less than one grid step per axis, and the points that fall inside
are dropped. The checks read the built hull back with ``getMeshData`` (the child's vertices in the link frame).
"""

from __future__ import annotations

import locale
import tempfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull  # type: ignore[import-untyped]

from backends.errors import UnsupportedFeature
from backends.geometry import quat_from_axis_angle
from backends.registry import create_backend
from backends.testing import worlds as w
from backends.testing.worlds import ZERO
from backends.types import BodySpec, Mesh, Motion, PlacedShape, Quat, Shape, ShapeKind, Vec3
from runner.compile.program import build_program
from runner.language.load import load_scenario
from runner.survey.models import find_models
from runner.survey.run import run_survey
from runner.survey.table import RAN
from tests.ci.conftest import cli

p = pytest.importorskip("pybullet", reason="pybullet is a base dependency")

GRID = 10216  # btConvexHullComputer: the hull's extent per axis in integer steps
F32 = 2.0**-24  # float32's relative rounding (round to nearest)
ROUNDING = 1e-15  # m: the transforms into and out of the link frame, a few roundings of 2^-53 at under 1 m
BIKE, MICROTAUR = "bicycle/bike.urdf", "quadruped/microtaur/microtaur.urdf"


def _icosphere() -> Mesh:
    """A 0.15 m icosphere's 162 vertices, moved off the shape's origin by numbers no float32 holds."""
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.15)
    vertices = tuple((float(x), float(y), float(z)) for x, y, z in sphere.vertices + (0.2, -0.1, 1.0 / 30.0))
    faces = tuple((int(a), int(b), int(c)) for a, b, c in sphere.faces)
    return Mesh(vertices=vertices, faces=faces, source="icosphere")


def _rotation(q: Quat) -> np.ndarray:
    return np.array(p.getMatrixFromQuaternion([q[1], q[2], q[3], q[0]])).reshape(3, 3)


def _built_hull(mesh: Mesh, pos: Vec3, quat: Quat) -> np.ndarray:
    """The hull's vertices as Bullet holds them, in the shape's frame: built as the 2nd shape of a compound
    (after a box) by the adapter, read back with getMeshData."""
    from backends.pybullet._compound import compound_shape

    placed = (PlacedShape(Shape(ShapeKind.BOX, size=(0.2, 0.2, 0.2)), pos=(1.0, 0.0, 0.0)),
              PlacedShape(Shape(ShapeKind.CONVEX, mesh=mesh), pos=pos, quat=quat))  # fmt: skip
    c = p.connect(p.DIRECT)
    try:
        uid = p.createMultiBody(1.0, compound_shape(p, c, placed, ZERO), physicsClientId=c)
        linked = np.array(p.getMeshData(uid, -1, collisionShapeIndex=1, physicsClientId=c)[1])
    finally:
        p.disconnect(physicsClientId=c)
    return (linked - np.array(pos)) @ _rotation(quat)  # R^T (x - pos), row by row


def test_a_hull_among_shapes_is_bullets_hull_of_its_vertices() -> None:
    """Every built vertex is a given one within the derived bound per axis (one grid step, float32 rounding,
    the frames' rounding), and every given vertex lies within the built hull but for that much: a hull
    misplaced, turned or missing fails by 0.1 m or more."""
    mesh = _icosphere()
    given = np.array(mesh.vertices)
    built = _built_hull(mesh, (-0.3, 0.2, 0.1), quat_from_axis_angle((1.0, 1.0, 0.0), 0.5))
    rounded = given.astype(np.float32).astype(np.float64)
    bound = (rounded.max(0) - rounded.min(0)) / GRID + F32 * np.abs(given) + ROUNDING  # per given vertex, per axis
    within = (np.abs(built[:, None, :] - given[None, :, :]) <= bound[None, :, :]).all(axis=2)
    assert 4 <= len(built) <= len(given)
    assert within.any(axis=1).all(), built[~within.any(axis=1)]
    hull = ConvexHull(built)
    outside = hull.equations[:, :3] @ given.T + hull.equations[:, 3:4]
    assert outside.max() <= float(np.linalg.norm(bound.max(0))), outside.max()


def test_a_float32_hull_builds_as_from_memory() -> None:
    """Vertices a float32 holds (an STL mesh's) survive the OBJ file unchanged: the compound's hull is the
    one createCollisionShape builds from the same vertices in memory, to the last bit."""
    sphere = _icosphere()
    vertices = np.array(sphere.vertices).astype(np.float32).astype(np.float64)
    mesh = Mesh(vertices=tuple((x, y, z) for x, y, z in vertices.tolist()), faces=sphere.faces)
    from_file = _built_hull(mesh, ZERO, w.IDENTITY)
    c = p.connect(p.DIRECT)
    try:
        shape = p.createCollisionShape(p.GEOM_MESH, vertices=vertices.tolist(), physicsClientId=c)
        uid = p.createMultiBody(1.0, shape, physicsClientId=c)
        from_memory = np.array(p.getMeshData(uid, -1, collisionShapeIndex=0, physicsClientId=c)[1])
    finally:
        p.disconnect(physicsClientId=c)
    assert from_file.shape == from_memory.shape
    assert np.array_equal(from_file[np.lexsort(from_file.T)], from_memory[np.lexsort(from_memory.T)])


def test_hull_files_are_gone_after_the_build_and_after_an_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from backends.pybullet._compound import compound_shape

    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    _built_hull(_icosphere(), ZERO, w.IDENTITY)
    assert list(folder.iterdir()) == []
    c = p.connect(p.DIRECT)
    p.disconnect(physicsClientId=c)  # the build's engine call fails: the client is gone
    placed = (PlacedShape(Shape(ShapeKind.SPHERE, radius=0.1)), PlacedShape(Shape(ShapeKind.CONVEX, mesh=_icosphere())))
    with pytest.raises(p.error, match="Not connected"):
        compound_shape(p, c, placed, ZERO)
    assert list(folder.iterdir()) == []


def test_a_temporary_folder_bullet_cannot_read_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """pybullet.c takes the path as ASCII: a non-ASCII temporary folder is refused naming TMPDIR, not built
    without its hull."""
    folder = tmp_path / "tmp-\u00e9t\u00e9"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    with pytest.raises(UnsupportedFeature, match="TMPDIR"):
        _built_hull(_icosphere(), ZERO, w.IDENTITY)
    assert list(folder.iterdir()) == []


def test_a_locale_with_a_decimal_comma_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """Bullet reads the numbers with the C library's atof, which follows LC_NUMERIC: under a decimal comma it
    would read 0.15 as 0. This machine has no such locale (`locale -a`: C, C.utf8, POSIX), so the C library's
    answer is replaced by one with a comma; the build is refused, not made of zeros."""
    conv = dict(locale.localeconv(), decimal_point=",")
    monkeypatch.setattr(locale, "localeconv", lambda: conv)
    with pytest.raises(UnsupportedFeature, match="LC_NUMERIC"):
        _built_hull(_icosphere(), ZERO, w.IDENTITY)


def _boxes(n: int) -> BodySpec:
    shapes = tuple(PlacedShape(Shape(ShapeKind.BOX, size=(0.1, 0.1, 0.1)), pos=(0.2 * i, 0.0, 0.0)) for i in range(n))
    return BodySpec("row", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), 1.0, (0.1, 0.1, 0.1), (0.0, 0.0, 1.0),
                    w.IDENTITY, shapes=shapes)  # fmt: skip


def test_a_compound_of_more_shapes_than_pybullet_holds_is_refused() -> None:
    """PyBullet's createCollisionShapeArray keeps 16 shapes and drops the rest without a word (20 boxes built
    16): 16 build, all of them; 17 are refused up front, naming the limit."""
    with create_backend("pybullet", w.world("sixteen", [_boxes(16)], gravity=ZERO)) as sim:
        model = sim.imported_model()
        assert model is not None and model.bodies[0].shapes == 16
    with pytest.raises(UnsupportedFeature, match="a compound of 17 shapes .* at most 16"):
        create_backend("pybullet", w.world("seventeen", [_boxes(17)], gravity=ZERO))


# --- the pybullet_data models PyBullet refused before ----------------------------------------------------------


def _scenario(tmp_path: Path, model: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: compound\nworld: {dt: 0.002, duration: 0.5}\n"
        "bodies:\n  ground: {plane: {}, motion: static}\n"
        f"robots:\n  r: {{urdf: '@pybullet_data/{model}', pos: [0, 0, 1]}}\n"
    )
    return path


def test_the_bike_builds_as_load_urdf_builds_it(tmp_path: Path) -> None:
    """bike.urdf's frameLink (two hulls, STL meshes) against pybullet's own loadURDF of the file: the same mass
    (5 kg), inertia (0.1 kg m^2 about each axis) and centre of mass (at the 1 m start, to rounding), two
    collision shapes, and each hull within one grid step of loadURDF's (both Bullet's hull of the same float32
    points, loadURDF's from all of the STL's points, ours from their hull: points just inside may come out on
    another grid point, less than one step per axis from it)."""
    import pybullet_data

    world = build_program(load_scenario(_scenario(tmp_path, BIKE))).world
    i = [b.name for b in world.bodies].index("r.frameLink")
    c = p.connect(p.DIRECT)
    try:
        uid = p.loadURDF(str(Path(pybullet_data.getDataPath()) / BIKE), [0, 0, 1], flags=p.URDF_USE_INERTIA_FROM_FILE,
                         physicsClientId=c)  # fmt: skip
        mass, _, inertia = p.getDynamicsInfo(uid, -1, physicsClientId=c)[:3]
        com, orn = p.getBasePositionAndOrientation(uid, physicsClientId=c)
        theirs = [np.array(p.getMeshData(uid, -1, collisionShapeIndex=k, physicsClientId=c)[1]) @ _rotation(
            (orn[3], orn[0], orn[1], orn[2])).T + com for k in (0, 1)]  # fmt: skip
    finally:
        p.disconnect(physicsClientId=c)
    with create_backend("pybullet", world) as sim:
        model = sim.imported_model()
        assert model is not None
        ours_body = next(b for b in model.bodies if b.name == "r.frameLink")
        c, uid, link = sim._c, sim._layout.uid[i], sim._layout.link[i]  # type: ignore[attr-defined]
        base, orn = p.getBasePositionAndOrientation(uid, physicsClientId=c)
        ours = [np.array(p.getMeshData(uid, link, collisionShapeIndex=k, physicsClientId=c)[1]) @ _rotation(
            (orn[3], orn[0], orn[1], orn[2])).T + base for k in (0, 1)]  # fmt: skip
    assert (ours_body.mass, ours_body.inertia, ours_body.shapes) == (mass, tuple(sorted(inertia)), 2)
    assert ours_body.com == pytest.approx((com[0], com[1], com[2] - 1.0), abs=1e-12)  # the body frame starts at 1 m
    for a, b in zip(ours, theirs, strict=True):
        step = float(np.linalg.norm((b.max(0) - b.min(0)) / GRID)) + ROUNDING
        for one, other in ((a, b), (b, a)):
            hull = ConvexHull(one)
            assert (hull.equations[:, :3] @ other.T + hull.equations[:, 3:4]).max() <= step


def test_bike_and_microtaur_run_on_pybullet_in_the_survey() -> None:
    """The survey's cells that were refused ("a compound with a mesh among other shapes") run (docs/robots.md)."""
    done = run_survey(find_models([f"@pybullet_data/{BIKE}", f"@pybullet_data/{MICROTAUR}"]), ["pybullet"], 0.5, jobs=1)
    assert {label: cells["pybullet"].kind for label, cells in done.rows.items()} == {
        f"@pybullet_data/{BIKE}": RAN,
        f"@pybullet_data/{MICROTAUR}": RAN,
    }, done.rows


def test_the_bikes_trace_is_the_same_bytes_twice(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The hull files' folder differs between runs; nothing of it reaches the trace."""
    scenario = _scenario(tmp_path, BIKE)
    traces = []
    for run in ("one", "two"):
        code, out = cli(capsys, "run", scenario, "--backend", "pybullet", "--out", tmp_path / run)
        assert code == 0, out
        (trace,) = sorted((tmp_path / run).rglob("*.mcap"))
        traces.append(trace.read_bytes())
    assert len(traces[0]) > 0 and traces[0] == traces[1]
