"""ODE's contacts of a pair with a triangle-mesh geom (backends/ode/_manifold.py): each distinct point once,
four at most (docs/backends/ode.md, "Robots").

ODE's trimesh-plane collider reports a touching vertex once for every triangle around it, so a hull's face
on a plane gives identical contacts, rows only the world's CFM keeps apart; pybullet_data's laikago landing
made Dantzig's LCP give up steps that way (tests/integration/test_survey_energy.py runs the file).
"""

from __future__ import annotations

import pytest

pytest.importorskip("panda3d.ode")

from panda3d.ode import OdeUtil  # noqa: E402 - after the skip guard

from backends.ode import OdeBackend  # noqa: E402
from backends.ode._manifold import MESH_CONTACTS, spread  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.types import BodySpec, CompiledWorld, Motion, Shape, ShapeKind  # noqa: E402

SIZE = (0.3, 0.2, 0.1)
#: corner positions: the resting box has no horizontal load, so only float32 rounding of its pose and of the
#: points (|p| < 0.2 m: 2.4e-8 m an operation) moves them; 1e-6 m leaves room for 40 such roundings
AT = 1e-6
#: the four normal forces sum to the weight at rest, to float32 rounding in the LCP and CFM's creep (the
#: rest velocity CFM * F / h per row is not exactly 0): relative 1e-4
WEIGHT = 1e-4


def _hull_on_the_ground() -> tuple[CompiledWorld, float]:
    mass, inertia = w.box_mass(SIZE, 500.0)
    hull = Shape(ShapeKind.CONVEX, mesh=w.box_hull(SIZE))
    body = BodySpec("hull", Motion.DYNAMIC, hull, mass, inertia, (0.0, 0.0, SIZE[2] / 2 + 0.01), w.IDENTITY)
    return w.world("hull", [w.ground(), body]), mass


def test_odes_trimesh_plane_collider_repeats_each_touching_vertex() -> None:
    """The cause, in ODE itself: the hull box resting on the plane collides with more contacts than corners,
    at only its four bottom corners (a vertex once per triangle around it: 18 contacts in ODE 0.13.1)."""
    world, _ = _hull_on_the_ground()
    sim = OdeBackend(world)
    with sim:
        for _ in range(100):
            sim.step()
        scene = sim._scene
        hull, plane = ([g for g in scene.geoms if scene.geom_index[hash(g.getId())] == k][0] for k in (1, 0))
        entry = OdeUtil.collide(hull, plane, 150)
        points = {tuple(g.getPos()) for g in entry.getContactGeoms()}
    assert len(points) == 4
    assert entry.getNumContacts() > len(points)


def test_a_hull_box_rests_on_its_four_corners_once_each() -> None:
    world, mass = _hull_on_the_ground()
    with OdeBackend(world) as sim:
        for _ in range(100):
            sim.step()
        points = sim.contact_points()
        state = sim.body_states()
    corners = sorted((sx * SIZE[0] / 2, sy * SIZE[1] / 2) for sx in (-1, 1) for sy in (-1, 1))
    got = sorted((p.pos[0], p.pos[1]) for p in points)
    assert len(got) == 4
    for (x, y), (cx, cy) in zip(got, corners, strict=True):
        assert abs(x - cx) <= AT and abs(y - cy) <= AT, (got, corners)
    weight = mass * w.G
    assert abs(sum(p.force for p in points) - weight) <= WEIGHT * weight
    assert all(p.force > 0.0 for p in points)  # each corner carries part of it
    assert state.pos[1][2] == pytest.approx(SIZE[2] / 2, abs=2e-3)  # the contract's resting-height tolerance


def test_spread_keeps_one_of_each_point_and_four_that_span_the_patch() -> None:
    """A 3 x 3 patch given twice (ODE's repeats), the centre deepest: the centre (deepest) and three corners,
    each the first of its copies, spanning half the patch's area (the deepest point is kept, as Bullet keeps it)."""
    grid = [(float(x), float(y), 0.0) for x in (-1, 0, 1) for y in (-1, 0, 1)]
    points = grid + grid
    depths = [2e-3 if p == (0.0, 0.0, 0.0) else 1e-3 for p in points]
    kept = spread(points, depths)
    assert len(kept) == MESH_CONTACTS
    assert all(k < len(grid) for k in kept)  # the first copy of each
    assert grid.index((0.0, 0.0, 0.0)) in kept
    assert sum(1 for k in kept if abs(grid[k][0]) == 1.0 and abs(grid[k][1]) == 1.0) == 3


def test_distinct_points_up_to_four_are_all_kept() -> None:
    points = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)]
    assert spread(points, [1e-3] * len(points)) == [0, 1, 3]
