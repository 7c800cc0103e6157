"""The shared backend suite for robot bodies (issue 22): compound shapes, COM offsets, convex hulls and
excluded pairs, run for every backend that declares the capability (the capability list is the documented
gap: a backend without it refuses robot scenarios up front, docs/robots.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from backends.base import Backend
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
    Vec3,
)

from . import worlds as w
from .tolerances import tol
from .worlds import ZERO, G, make_backend, require

# --- compound bodies ----------------------------------------------------------------------------------

#: Two 0.1 m cubes at (+-0.3, 0, -0.1) in the body frame: the frame rests 0.05 + 0.1 above the plane.
_FEET = (
    PlacedShape(Shape(ShapeKind.BOX, size=(0.1, 0.1, 0.1)), pos=(0.3, 0.0, -0.1)),
    PlacedShape(Shape(ShapeKind.BOX, size=(0.1, 0.1, 0.1)), pos=(-0.3, 0.0, -0.1)),
)
_FEET_MASS, _FEET_INERTIA = 2.0, (0.01, 0.1, 0.1)  # given, never derived from the shapes


def _compound(shapes: tuple[PlacedShape, ...], z: float, gravity: Vec3 = (0.0, 0.0, -G)) -> CompiledWorld:
    feet = BodySpec(
        "feet", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), _FEET_MASS, _FEET_INERTIA, (0.0, 0.0, z),
        w.IDENTITY, shapes=shapes,
    )
    return w.world("compound", [w.ground(), feet], gravity=gravity)


def test_compound_rests_on_its_shapes(backend_name: str, backend_cls: type[Backend]) -> None:
    """A body with only two feet away from its origin rests level on them: frame at 0.15 m.

    Tolerance ``resting_height`` (the primitive shapes' resting depth, same contact); level: the two
    feet carry the same load, so any tilt is that depth difference over the 0.6 m between them.
    """
    require(backend_cls, Capability.SHAPE_COMPOUND)
    with make_backend(backend_name, _compound(_FEET, 0.16)) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    depth = tol("resting_height", backend_name)
    assert s.pos[1, 2] == pytest.approx(0.15, abs=depth)
    assert np.linalg.norm(s.lin_vel[1]) < 0.01
    tilt = 2.0 * math.asin(min(1.0, float(np.linalg.norm(s.quat[1, 1:]))))
    assert tilt < 2.0 * depth / 0.6


def test_compound_without_shapes_touches_nothing(backend_name: str, backend_cls: type[Backend]) -> None:
    """An empty shape tuple: the body falls through the plane as in free fall (ODE's semi-implicit Euler)."""
    require(backend_cls, Capability.SHAPE_COMPOUND)
    world = _compound((), 0.2)
    with make_backend(backend_name, world) as sim:
        for _ in range(40):
            sim.step()
            assert sim.contacts() == []
        s = sim.body_states()
    n = 40
    assert s.pos[1, 2] == pytest.approx(0.2 - G * world.dt**2 * n * (n + 1) / 2, abs=tol("free_fall", backend_name))


# --- COM offset: a physical pendulum ------------------------------------------------------------------

_L, _M, _THETA0 = 0.5, 1.0, 0.1
#: Principal moments about the COM and the rotation to their axes: 90 degrees about z, so the first
#: principal axis (0.05 kg m^2) is the body's y, the hinge axis. An adapter that drops ``inertia_quat``
#: swings with 0.08 instead.
_PRINCIPAL, _TURN_Z = (0.05, 0.08, 0.02), (math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4))


def _pendulum(dt: float) -> CompiledWorld:
    """The body frame at the hinge (0, 0, 1), its COM L below, released at THETA0 about +y."""
    q0 = (math.cos(_THETA0 / 2), 0.0, math.sin(_THETA0 / 2), 0.0)
    bob = BodySpec(
        "bob", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), _M, _PRINCIPAL, (0.0, 0.0, 1.0), q0,
        com=(0.0, 0.0, -_L), inertia_quat=_TURN_Z,
    )
    hinge = JointSpec("pivot", JointKind.HINGE, "bob", None, axis=(0.0, 1.0, 0.0), anchor=(0.0, 0.0, 1.0))
    return CompiledWorld(
        name="com-pendulum", gravity=(0.0, 0.0, -G), dt=dt, substeps=1, duration=1.0, bodies=(bob,),
        joints=(hinge,),
    )


def test_com_offset_physical_pendulum(backend_name: str, backend_cls: type[Backend]) -> None:
    """A body whose COM is L below its frame, hinged at its frame, has the physical pendulum's period.

    T = 2 pi sqrt(I_p / (m g L)) with I_p = I_c + m L^2 (parallel axes; I_c = 0.05 about the hinge axis,
    set through ``inertia_quat``), times 1 + theta0^2/16 for the amplitude (next term 11 theta0^4/3072 =
    3.6e-7). The quarter period is the first step at which the swing angle changes sign: that step is at
    most one dt late, and semi-implicit Euler's frequency error ((omega dt)^2/24 = 7e-7) is far below it,
    so the tolerance is dt. Dropping the COM offset gives no swing; dropping the axes' rotation, 17 ms.

    The states are the body FRAME's: its origin stays on the hinge (the joint's drift is bounded by one
    step of uncorrected gravity, g dt^2 = 1e-5 m, and corrected every step: 1e-3 m is a hundred of them) and
    its velocity is the origin's (below one step's g dt, where the COM moves at up to omega theta0 L = 0.2 m/s).
    """
    require(backend_cls, Capability.COM_OFFSET)
    require(backend_cls, Capability.SHAPE_COMPOUND)
    dt = 1e-3
    i_pivot = _PRINCIPAL[0] + _M * _L**2
    quarter = math.pi / 2 * math.sqrt(i_pivot / (_M * G * _L)) * (1 + _THETA0**2 / 16)
    crossing = math.nan
    with make_backend(backend_name, _pendulum(dt)) as sim:
        for k in range(1, 1000):
            sim.step()
            s = sim.body_states()
            assert np.linalg.norm(s.pos[0] - (0.0, 0.0, 1.0)) < 1e-3, f"step {k}"
            assert np.linalg.norm(s.lin_vel[0]) < G * dt, f"step {k}"
            qw, qy = s.quat[0, 0], s.quat[0, 2]
            if 2.0 * math.atan2(qy, qw) <= 0.0:
                crossing = k * dt
                break
    assert crossing == pytest.approx(quarter, abs=dt)


# --- convex hulls -------------------------------------------------------------------------------------


def _box_hull(half: float) -> Mesh:
    """A cube's 8 corners and 12 outward (counter-clockwise from outside) triangles."""
    h = half
    vertices = tuple((x, y, z) for x in (-h, h) for y in (-h, h) for z in (-h, h))  # index 4x + 2y + z
    faces = (
        (0, 1, 3), (0, 3, 2),  # x = -h
        (4, 6, 7), (4, 7, 5),  # x = +h
        (0, 4, 5), (0, 5, 1),  # y = -h
        (2, 3, 7), (2, 7, 6),  # y = +h
        (0, 2, 6), (0, 6, 4),  # z = -h
        (1, 5, 7), (1, 7, 3),  # z = +h
    )
    return Mesh(vertices, faces, "cube")


def test_box_hull_outward_faces() -> None:
    """The hull's triangles face outward: each normal points away from the centre (checks the fixture)."""
    mesh = _box_hull(0.1)
    v = np.asarray(mesh.vertices)
    for a, b, c in mesh.faces:
        normal = np.cross(v[b] - v[a], v[c] - v[a])
        assert float(normal @ (v[a] + v[b] + v[c])) > 0.0


def test_convex_hull_box_rests_at_half_height(backend_name: str, backend_cls: type[Backend]) -> None:
    """A 0.2 m cube given as a hull rests with its centre 0.1 m up (``resting_height`` as a box)."""
    require(backend_cls, Capability.SHAPE_CONVEX)
    mass, inertia = w.box_mass((0.2, 0.2, 0.2), 500.0)
    cube = BodySpec(
        "hull", Motion.DYNAMIC, Shape(ShapeKind.CONVEX, mesh=_box_hull(0.1)), mass, inertia, (0.0, 0.0, 0.11),
        w.IDENTITY,
    )
    with make_backend(backend_name, w.world("hull", [w.ground(), cube])) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
        contacts = sim.contacts()
    assert s.pos[1, 2] == pytest.approx(0.1, abs=tol("resting_height", backend_name))
    assert np.linalg.norm(s.lin_vel[1]) < 0.01
    assert [(c.a, c.b) for c in contacts] == [(0, 1)]


# --- excluded pairs -----------------------------------------------------------------------------------


def _overlap(excluded: bool) -> CompiledWorld:
    """Two 0.2 m boxes overlapping by half their width, no gravity."""
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0))
    b = w.box("b", (0.2, 0.2, 0.2), (0.1, 0.0, 1.0))
    world = w.world("overlap", [a, b], gravity=ZERO)
    if not excluded:
        return world
    return CompiledWorld(
        name=world.name, gravity=world.gravity, dt=world.dt, substeps=1, duration=world.duration,
        bodies=world.bodies, default_surface=world.default_surface, excluded_pairs=(("a", "b"),),
    )


def test_excluded_pair_does_not_push_apart(backend_name: str, backend_cls: type[Backend]) -> None:
    """Excluded, two overlapping boxes stay exactly where they are and report no contact; the same boxes
    not excluded are pushed apart (the check can fail)."""
    require(backend_cls, Capability.COLLISION_FILTER)
    with make_backend(backend_name, _overlap(excluded=True)) as sim:
        for _ in range(50):
            sim.step()
            assert sim.contacts() == []
        s = sim.body_states()
    # Unmoved up to the storage of the start pose: single-precision engines (ODE) round it to half an ulp,
    # 6e-8 at 1 m; nothing else may move them.
    assert s.pos[0] == pytest.approx((0.0, 0.0, 1.0), abs=1e-7)
    assert s.pos[1] == pytest.approx((0.1, 0.0, 1.0), abs=1e-7)
    with make_backend(backend_name, _overlap(excluded=False)) as sim:
        sim.step()
        touching = [(c.a, c.b) for c in sim.contacts()]
        for _ in range(49):
            sim.step()
        s = sim.body_states()
    assert touching == [(0, 1)]
    assert s.pos[1, 0] - s.pos[0, 0] > 0.1 + 1e-3


def test_com_offset_reset_body_places_the_frame(backend_name: str, backend_cls: type[Backend]) -> None:
    """``reset_body`` gives the body FRAME's pose and its origin's velocity; they read back as given.

    A spinning body's origin 0.5 m from its COM moves at v_com + w x (origin - com): an adapter that set
    the COM to the frame's pose, or the COM's velocity to the origin's, reads back 0.5 m or 1 m/s off.
    Tolerance: values of order 1 stored by single-precision engines, a few float32 ulps (1.2e-7): 1e-6.
    """
    require(backend_cls, Capability.COM_OFFSET)
    require(backend_cls, Capability.SHAPE_COMPOUND)
    world = CompiledWorld(
        name="reset", gravity=ZERO, dt=0.01, substeps=1, duration=1.0,
        bodies=(BodySpec("bob", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), _M, _PRINCIPAL, ZERO, w.IDENTITY,
                         com=(0.0, 0.0, -_L), inertia_quat=_TURN_Z),),
    )  # fmt: skip
    quat = (math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4))
    with make_backend(backend_name, world) as sim:
        sim.step()
        sim.reset_body(0, (1.0, 2.0, 3.0), quat, (0.5, 0.0, 0.0), (0.0, 2.0, 0.0))
        s = sim.body_states()
    assert s.pos[0] == pytest.approx((1.0, 2.0, 3.0), abs=1e-6)
    assert s.quat[0] * np.sign(s.quat[0, 0]) == pytest.approx(quat, abs=1e-6)
    assert s.lin_vel[0] == pytest.approx((0.5, 0.0, 0.0), abs=1e-6)
    assert s.ang_vel[0] == pytest.approx((0.0, 2.0, 0.0), abs=1e-6)
