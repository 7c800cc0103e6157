"""The robot part of the backend contract (backends/types.py): compound bodies, COM offsets, convex hulls and
excluded pairs, run on every backend that declares the capability (the capability list is the documented gap:
docs/robots.md). Expectations are analytic; tolerances come from tests/backends/tolerances.py or are derived here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from backends.base import Backend
from backends.geometry import quat_from_axis_angle, quat_rotate
from backends.types import (
    BodySpec,
    Capability,
    CompiledWorld,
    JointKind,
    JointSpec,
    Mesh,
    Motion,
    PlacedShape,
    Shape,
    ShapeKind,
)

from . import worlds as w
from .tolerances import tol

EMPTY = Shape(ShapeKind.COMPOUND)


# --- compound bodies ------------------------------------------------------------------------------


def test_compound_rests_on_its_shapes(backend_name: str, backend_cls: type[Backend]) -> None:
    """Two 0.1 m cubes at x = +-0.2 of a body whose own origin holds nothing: it rests with its frame at the
    cubes' half height (0.05 m), level, and only the cubes touch the ground."""
    w.require(backend_cls, Capability.SHAPE_COMPOUND)
    cube = Shape(ShapeKind.BOX, size=(0.1, 0.1, 0.1))
    shapes = (PlacedShape(cube, (0.2, 0.0, 0.0)), PlacedShape(cube, (-0.2, 0.0, 0.0)))
    # mass and inertia are the body's, given (two 1 kg cubes: I from the parallel axis theorem)
    inertia = (0.0033, 0.0833, 0.0833)
    spec = BodySpec("dumbbell", Motion.DYNAMIC, EMPTY, 2.0, inertia, (0.0, 0.0, 0.06), w.IDENTITY, shapes=shapes)
    with w.make_backend(backend_name, w.world("compound", [w.ground(), spec])) as sim:
        for _ in range(100):
            sim.step()
        s, touching = sim.body_states(), {(c.a, c.b) for c in sim.contacts()}
    assert s.pos[1, 2] == pytest.approx(0.05, abs=tol("resting_height", backend_name))
    assert abs(s.quat[1, 0]) == pytest.approx(1.0, abs=1e-6)  # level: both cubes carry it
    assert touching == {(0, 1)}


def test_compound_without_shapes_never_touches(backend_name: str, backend_cls: type[Backend]) -> None:
    """An empty compound (a link that collides with nothing) falls through the ground in free fall."""
    w.require(backend_cls, Capability.SHAPE_COMPOUND)
    spec = BodySpec("ghost", Motion.DYNAMIC, EMPTY, 1.0, (0.1, 0.1, 0.1), (0.0, 0.0, 0.05), w.IDENTITY)
    with w.make_backend(backend_name, w.world("ghost", [w.ground(), spec], steps=20)) as sim:
        for _ in range(20):
            sim.step()
            assert sim.contacts() == []
        z = sim.body_states().pos[1, 2]
    # semi-implicit Euler: z_n = z0 - g h^2 n(n+1)/2
    assert z == pytest.approx(0.05 - w.G * 0.01**2 * 20 * 21 / 2, abs=tol("free_fall", backend_name))


# --- COM offsets ----------------------------------------------------------------------------------

#: The physical pendulum: a body hinged at its own origin, its COM D below it, principal axes turned 90
#: degrees about x, so the moment about the hinge axis (body y) is the THIRD principal moment.
D, MASS, MOMENTS = 0.3, 2.0, (0.01, 0.02, 0.05)
TURN = quat_from_axis_angle((1.0, 0.0, 0.0), math.pi / 2)


def _pendulum(theta0: float) -> CompiledWorld:
    start = quat_from_axis_angle((0.0, 1.0, 0.0), theta0)
    spec = BodySpec(
        "bob", Motion.DYNAMIC, EMPTY, MASS, MOMENTS, (0.0, 0.0, 1.0), start, com=(0.0, 0.0, -D), inertia_quat=TURN
    )
    hinge = JointSpec("pivot", JointKind.HINGE, "bob", None, axis=(0.0, 1.0, 0.0), anchor=(0.0, 0.0, 1.0))
    return w.world("physical-pendulum", [spec], joints=(hinge,), dt=0.001, steps=3000)


def _angle(quat: np.ndarray) -> float:
    """Rotation about +y of a quaternion that only turns about y."""
    return 2.0 * math.atan2(float(quat[2]), float(quat[0]))


def test_com_offset_pendulum_period(backend_name: str, backend_cls: type[Backend]) -> None:
    """Period of the physical pendulum T = 2 pi sqrt(I_O / (m g d)) (1 + theta0^2/16), I_O = I_about_axis + m d^2
    with the moment about the axis the third principal one (inertia_quat). The body frame's origin sits on the
    hinge: its reported position stays at the anchor and its velocity (the ORIGIN's) at zero."""
    w.require(backend_cls, Capability.COM_OFFSET)
    theta0 = 0.05
    i_pivot = MOMENTS[2] + MASS * D * D
    expected = 2 * math.pi * math.sqrt(i_pivot / (MASS * w.G * D)) * (1 + theta0**2 / 16)
    world = _pendulum(theta0)
    angles, origin_speed, origin_drift = [], 0.0, 0.0
    with w.make_backend(backend_name, world) as sim:
        for _ in range(3000):
            sim.step()
            s = sim.body_states()
            angles.append(_angle(s.quat[0]))
            origin_speed = max(origin_speed, float(np.linalg.norm(s.lin_vel[0])))
            origin_drift = max(origin_drift, float(np.linalg.norm(s.pos[0] - np.array([0.0, 0.0, 1.0]))))
    # downward zero crossings, linearly interpolated between steps
    a, h = np.array(angles), world.dt
    crossings = [(k + a[k] / (a[k] - a[k + 1])) * h for k in range(len(a) - 1) if a[k] > 0 >= a[k + 1]]
    period = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    # Tolerance: semi-implicit Euler's period error (omega h)^2/24 = 2e-7 relative (omega 2.9 rad/s, h 1 ms),
    # the amplitude series' next term 11 theta0^4 / 3072 = 2e-8, interpolating a crossing: under h^2 omega^2
    # theta0 / 8 in time = 5e-11 s. All far below 1e-4 s (1e-4 relative of T = 1.1 s), the bound used.
    assert period == pytest.approx(expected, abs=1e-4)
    # the origin is on the hinge axis: reduced-coordinate engines hold it to rounding (pivot_distance bound)
    assert origin_drift < tol("pivot_distance", backend_name)
    assert origin_speed < tol("pivot_distance", backend_name) / h  # the drift's largest rate over one step


def test_com_offset_reset_places_the_body_frame(backend_name: str, backend_cls: type[Backend]) -> None:
    """reset_body places the body FRAME and its ORIGIN's velocity; states read back unchanged."""
    w.require(backend_cls, Capability.COM_OFFSET)
    spec = BodySpec(
        "lump", Motion.DYNAMIC, EMPTY, 1.0, MOMENTS, (0.0, 0.0, 2.0), w.IDENTITY, com=(0.1, 0.2, 0.3), inertia_quat=TURN
    )
    pos, quat = (1.0, 2.0, 3.0), quat_from_axis_angle((0.0, 0.0, 1.0), 0.7)
    lin, ang = (0.5, 0.0, 0.0), (0.0, 0.0, 2.0)
    with w.make_backend(backend_name, w.world("lump", [spec], gravity=(0.0, 0.0, 0.0))) as sim:
        sim.reset_body(0, pos, quat, lin, ang)
        s, exact = sim.body_states(), tol("fresh_states", backend_name)
        assert s.pos[0] == pytest.approx(pos, abs=exact) and s.quat[0] == pytest.approx(quat, abs=exact)
        assert s.lin_vel[0] == pytest.approx(lin, abs=exact) and s.ang_vel[0] == pytest.approx(ang, abs=exact)
        sim.step()
        s = sim.body_states()
    # free of forces the COM moves straight on: v_com = v_origin + omega x (R com)
    arm = quat_rotate(quat, spec.com)
    v_com = np.array(lin) + np.cross(ang, arm)
    com_after = np.array(s.pos[0]) + np.array(quat_rotate(tuple(s.quat[0]), spec.com))
    assert com_after == pytest.approx(np.array(pos) + np.array(arm) + v_com * 0.01, abs=1e-9)


# --- convex hulls ---------------------------------------------------------------------------------


def _box_hull(size: tuple[float, float, float]) -> Mesh:
    """A box as 8 vertices and 12 outward triangles (counter-clockwise seen from outside)."""
    hx, hy, hz = (s / 2 for s in size)
    verts = tuple((sx * hx, sy * hy, sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1))
    quads = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))
    faces = tuple(t for a, b, c, d in quads for t in ((a, b, c), (a, c, d)))
    return Mesh(verts, faces, "box-hull")


def test_convex_hull_box_rests_at_half_height(backend_name: str, backend_cls: type[Backend]) -> None:
    """A hull box 0.2 x 0.2 x 0.1 dropped 1 cm rests with its centre at 0.05 m, as the primitive box does."""
    w.require(backend_cls, Capability.SHAPE_CONVEX)
    hull = Shape(ShapeKind.CONVEX, mesh=_box_hull((0.2, 0.2, 0.1)))
    mass, inertia = w.box_mass((0.2, 0.2, 0.1), 500.0)
    spec = BodySpec("hull", Motion.DYNAMIC, hull, mass, inertia, (0.0, 0.0, 0.06), w.IDENTITY)
    with w.make_backend(backend_name, w.world("hull", [w.ground(), spec])) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    assert s.pos[1, 2] == pytest.approx(0.05, abs=tol("hull_resting_height", backend_name))
    assert np.linalg.norm(s.lin_vel[1]) < 0.01


# --- excluded pairs -------------------------------------------------------------------------------


def _overlap(excluded: bool) -> CompiledWorld:
    """Two 0.2 m cubes overlapping by half their width, no gravity."""
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0))
    b = w.box("b", (0.2, 0.2, 0.2), (0.1, 0.0, 1.0))
    base = w.world("overlap", [a, b], gravity=(0.0, 0.0, 0.0), steps=20)
    if not excluded:
        return base
    return CompiledWorld(**{**base.__dict__, "excluded_pairs": (("a", "b"),)})


@pytest.mark.parametrize("excluded", [True, False], ids=["excluded", "colliding"])
def test_excluded_pair_never_touches(backend_name: str, backend_cls: type[Backend], excluded: bool) -> None:
    """Excluded, the overlapping cubes stay put and never appear in contacts(); not excluded (the control
    that makes the test able to fail) they push apart."""
    w.require(backend_cls, Capability.COLLISION_FILTER)
    with w.make_backend(backend_name, _overlap(excluded)) as sim:
        listed = 0
        for _ in range(20):
            sim.step()
            listed += len(sim.contacts())
        s = sim.body_states()
    gap = float(s.pos[1, 0] - s.pos[0, 0])
    if excluded:
        assert listed == 0
        assert gap == pytest.approx(0.1, abs=1e-12) and float(np.abs(s.lin_vel).max()) == 0.0
    else:
        assert listed > 0 and gap > 0.1 + 1e-3
