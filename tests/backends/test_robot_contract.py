"""The robot part of the backend contract (backends/base.py, "Robots"), run on every backend that declares it.

Each test needs a capability of ``backends.types.ROBOT_CAPABILITIES`` and runs only where the backend
declares it (``worlds.require``: the capability list is the documented gap, the runner refuses such worlds
up front on the others). Expectations are analytic; tolerances are derived beside each check or shared
with the main suite (``tolerances.py``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import trimesh

from backends.base import Backend
from backends.types import BodySpec, Capability, JointKind, JointSpec, Mesh, Motion, PlacedShape, Shape, ShapeKind
from tests.backends import worlds as w
from tests.backends.tolerances import tol

# --- helpers ----------------------------------------------------------------------------------------


def _quat_about(axis: tuple[float, float, float], angle: float) -> tuple[float, float, float, float]:
    s = math.sin(angle / 2)
    return (math.cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s)


def _box_hull(size: tuple[float, float, float]) -> Shape:
    """A box as a convex mesh (trimesh's 8 vertices, 12 outward triangles), centred on the shape frame."""
    box = trimesh.creation.box(extents=size)
    vertices = tuple((float(x), float(y), float(z)) for x, y, z in box.vertices)
    faces = tuple((int(a), int(b), int(c)) for a, b, c in box.faces)
    return Shape(ShapeKind.CONVEX, mesh=Mesh(vertices, faces, source="box"))


def _compound(
    name: str,
    shapes: tuple[PlacedShape, ...],
    pos: tuple[float, float, float],
    mass: float,
    inertia: tuple[float, float, float],
    **kw: object,
) -> BodySpec:
    return BodySpec(
        name, Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), mass, inertia, pos, w.IDENTITY, shapes=shapes, **kw
    )  # type: ignore[arg-type]


# --- shape:compound -----------------------------------------------------------------------------------


def test_compound_body_rests_on_its_placed_shapes(backend_name: str, backend_cls: type[Backend]) -> None:
    """A dumbbell: two shapes at x = +-0.2 and nothing at the origin, one of them turned.

    The right one is a 0.1 x 0.1 x 0.3 box turned 90 degrees about x (so 0.1 high): both ends rest flat only
    if each shape sits at its local pose, and the body frame rests at z = 0.05 (0.15 if the turn were
    ignored, tilted if either offset were). A sphere of 0.03 m around the body's origin (x = 0, 1 cm
    above the ground) falls untouched to the ground: no shape at the origin. A body with no shapes falls
    through the ground. Mass and inertia are the body's (set to a value the shapes would not give: 3 kg).
    """
    w.require(backend_cls, Capability.SHAPE_COMPOUND)
    turned = _quat_about((1.0, 0.0, 0.0), math.pi / 2)
    shapes = (
        PlacedShape(Shape(ShapeKind.BOX, size=(0.1, 0.1, 0.1)), pos=(-0.2, 0.0, 0.0)),
        PlacedShape(Shape(ShapeKind.BOX, size=(0.1, 0.1, 0.3)), pos=(0.2, 0.0, 0.0), quat=turned),
    )
    dumbbell = _compound("dumbbell", shapes, (0.0, 0.0, 0.06), 3.0, (0.01, 0.05, 0.05))
    ghost = _compound("ghost", (), (1.0, 0.0, 0.2), 1.0, (0.01, 0.01, 0.01))
    ball = w.sphere("ball", 0.03, (0.0, 0.0, 0.04), density=500.0)
    world = w.world("compound", [w.ground(), dumbbell, ghost, ball])
    with w.make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
        touching = {(c.a, c.b) for c in sim.contacts()}
    rest = tol("resting_height", backend_name)  # one landing from 1 cm, as the main suite's shapes
    assert s.pos[1, 2] == pytest.approx(0.05, abs=rest)
    # Level: both ends down. An ignored turn leaves the right end 0.1 m lower (0.15 against 0.05 below the
    # frame): a tilt of 0.25 rad; the resting tolerance at either end over the 0.4 m span bounds a level rest.
    tilt = 2 * math.acos(min(1.0, abs(float(s.quat[1, 0]))))
    assert tilt < 2 * rest / 0.4
    assert (0, 1) in touching
    assert s.pos[3, 2] == pytest.approx(0.03, abs=rest)  # the ball on the ground, not on the dumbbell
    assert (1, 3) not in touching
    # The empty body: 1 s of free fall from 0.2 m, far below the ground (semi-implicit Euler: 0.2 - g*1.01/2).
    assert s.pos[2, 2] == pytest.approx(0.2 - w.G * 1.0 * 1.01 / 2, abs=tol("free_fall", backend_name))


# --- body:com-offset ----------------------------------------------------------------------------------


def test_com_offset_pendulum_has_the_physical_pendulums_period(backend_name: str, backend_cls: type[Backend]) -> None:
    """A body whose frame sits at a hinge (about world x) with its COM L = 0.3 m below, released at 0.1 rad.

    Physical pendulum: T0 = 2 pi sqrt(I / (m g L)) with I = I_c + m L^2, I_c the moment about the COM along
    the hinge axis; at amplitude a the period is T0 (1 + a^2/16 + 11 a^4/3072 + ...). The principal moments
    are (0.001, 0.05, 0.002) along axes turned 90 degrees about z (``inertia_quat``), so the body's x axis
    carries the principal 0.05: I = 0.14, T = 1.37126 s. Mapping the inertia without that turn gives 0.001
    (T 1.1049 s, -19 %), about the frame origin instead of the COM (I + m L^2) 1.7565 s (+28 %), a COM at
    the origin no swing at all.

    Relative tolerance 1e-3 (derived): the series' next term 11 a^6 ... < 1e-8 of T after the a^4 term
    kept; semi-implicit Euler shifts omega by (omega h)^2 / 24 = 3.5e-6 at h = 0.002 s (omega 4.585
    rad/s); zero crossings interpolated linearly within a step, where the angle is linear to
    (omega h)^2 = 8e-5 of a step; a maximal-coordinate hinge (ODE) drifts its anchor by about
    (a omega)^2 L h^2 = 2.5e-7 m. Every one is at most a few 1e-6; 1e-3 leaves room for float32 engines
    and is 190 times smaller than the inertia-axis error it must catch.

    The body frame stays at the pivot: its position within ``pivot_distance`` of the anchor, and its
    reported velocity (of its origin) below 0.01 m/s where the COM moves at up to a omega L = 0.15 m/s.
    """
    w.require(backend_cls, Capability.COM_OFFSET)
    w.require(backend_cls, Capability.JOINT_HINGE)
    m, length, a = 1.0, 0.3, 0.1
    moments = (0.001, 0.05, 0.002)
    i_hinge = moments[1] + m * length * length
    t0 = 2 * math.pi * math.sqrt(i_hinge / (m * w.G * length))
    period = t0 * (1 + a * a / 16 + 11 * a**4 / 3072)
    start = _quat_about((1.0, 0.0, 0.0), a)
    anchor = (0.0, 0.0, 1.0)
    bob = BodySpec(
        "bob",
        Motion.DYNAMIC,
        Shape(ShapeKind.COMPOUND),
        m,
        moments,
        anchor,
        start,
        com=(0.0, 0.0, -length),
        inertia_quat=_quat_about((0.0, 0.0, 1.0), math.pi / 2),
    )
    hinge = JointSpec("pivot", JointKind.HINGE, "bob", None, axis=(1.0, 0.0, 0.0), anchor=anchor)
    dt = 0.002
    world = w.world("com-pendulum", [bob], joints=(hinge,), dt=dt, steps=1500)
    angles, drift, speed = [0.0], 0.0, 0.0
    with w.make_backend(backend_name, world) as sim:
        for _ in range(1500):
            sim.step()
            s = sim.body_states()
            angles.append(float(sim.joint_states().position[0]))
            drift = max(drift, float(np.linalg.norm(s.pos[0] - np.asarray(anchor))))
            speed = max(speed, float(np.linalg.norm(s.lin_vel[0])))
    theta = a + np.asarray(angles)  # the hinge counts from the start pose
    crossings = [
        dt * (k + theta[k] / (theta[k] - theta[k + 1]))
        for k in range(len(theta) - 1)
        if theta[k] > 0 >= theta[k + 1] or theta[k] < 0 <= theta[k + 1]
    ]
    assert len(crossings) >= 4, f"the pendulum did not swing: {len(crossings)} zero crossings"
    measured = (crossings[-1] - crossings[0]) / (len(crossings) - 1) * 2
    assert measured == pytest.approx(period, rel=1e-3)
    assert drift < tol("pivot_distance", backend_name)
    assert speed < 0.01


def test_force_acts_at_the_com(backend_name: str, backend_cls: type[Backend]) -> None:
    """Without gravity, 10 N for one step on a 2 kg body whose COM is 0.2 m off its frame: no rotation,
    and the frame (moving with the COM) at F dt / m = 0.05 m/s. At the frame's origin the same force would
    spin it at F d dt / I = 1 rad/s (d 0.2 m, I 0.02)."""
    w.require(backend_cls, Capability.COM_OFFSET)
    body = BodySpec(
        "body",
        Motion.DYNAMIC,
        Shape(ShapeKind.COMPOUND),
        2.0,
        (0.02, 0.02, 0.02),
        (0.0, 0.0, 1.0),
        w.IDENTITY,
        com=(0.2, 0.0, 0.0),
    )
    world = w.world("com-force", [body], gravity=(0.0, 0.0, 0.0))
    with w.make_backend(backend_name, world) as sim:
        sim.apply_force(0, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0))
        sim.step()
        s = sim.body_states()
    eps = tol("one_step_force", backend_name)
    assert s.ang_vel[0] == pytest.approx((0.0, 0.0, 0.0), abs=eps)
    assert s.lin_vel[0] == pytest.approx((0.0, 0.0, 0.05), abs=eps)


def test_free_body_spins_about_its_com_and_reports_its_frame(backend_name: str, backend_cls: type[Backend]) -> None:
    """Without gravity, a body whose COM is 0.2 m along its x axis, spinning at 1 rad/s about z with its frame
    origin moving at omega x (origin - COM) = (0, -0.2, 0) m/s: the COM stays put, and the reported state
    is the frame's: its origin on a circle of 0.2 m around the COM, its velocity omega x (pos - COM), 0.2 m/s.

    Tolerances (derived): an engine integrating the frame origin with semi-implicit Euler (a first-order
    step along a turning velocity) moves the COM outward by at most omega^2 r h^2 / 2 = 1e-5 m per step,
    1e-3 m over 100 steps: 2e-3 m on the COM. The velocity's direction follows the orientation; its
    relation to pos and COM is exact in any engine up to that same drift: 2e-3 m/s. An adapter reporting
    the COM (position 0.2 m off, velocity 0) misses both by a hundred times that.
    """
    w.require(backend_cls, Capability.COM_OFFSET)
    com = np.array([0.2, 0.0, 0.0])
    body = BodySpec("body", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), 1.0, (0.02, 0.02, 0.02), (0.0, 0.0, 1.0),
                    w.IDENTITY, lin_vel=(0.0, -0.2, 0.0), ang_vel=(0.0, 0.0, 1.0), com=(0.2, 0.0, 0.0))  # fmt: skip
    world = w.world("com-spin", [body], gravity=(0.0, 0.0, 0.0))
    with w.make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    qw, qx, qy, qz = (float(v) for v in s.quat[0])
    turn = 2 * math.atan2(qz, qw)  # about z only
    assert abs(qx) < tol("orientation", backend_name) and abs(qy) < tol("orientation", backend_name)
    com_world = s.pos[0] + np.array([math.cos(turn), math.sin(turn), 0.0]) * com[0]
    assert com_world == pytest.approx((0.2, 0.0, 1.0), abs=2e-3)
    assert turn == pytest.approx(1.0, abs=tol("orientation", backend_name))  # 1 s at 1 rad/s
    expected_vel = np.cross(s.ang_vel[0], s.pos[0] - com_world)
    assert s.lin_vel[0] == pytest.approx(expected_vel, abs=2e-3)
    assert float(np.linalg.norm(s.lin_vel[0])) == pytest.approx(0.2, abs=2e-3)


# --- shape:convex ---------------------------------------------------------------------------------------


def test_convex_hull_box_rests_at_its_half_height(backend_name: str, backend_cls: type[Backend]) -> None:
    """A 0.2 x 0.3 x 0.4 box given as a convex mesh, dropped 1 cm, rests with its centre at 0.2 m (level),
    as the main suite's primitive box does (same tolerance, same landing)."""
    w.require(backend_cls, Capability.SHAPE_COMPOUND)
    w.require(backend_cls, Capability.SHAPE_CONVEX)
    size = (0.2, 0.3, 0.4)
    mass, inertia = w.box_mass(size, 500.0)
    hull = _compound("hull", (PlacedShape(_box_hull(size)),), (0.0, 0.0, 0.21), mass, inertia)
    with w.make_backend(backend_name, w.world("hull", [w.ground(), hull])) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
        touching = {(c.a, c.b): c for c in sim.contacts()}
    assert s.pos[1, 2] == pytest.approx(0.2, abs=tol("resting_height", backend_name))
    assert np.linalg.norm(s.lin_vel[1]) < 0.01
    assert abs(float(s.quat[1, 0])) == pytest.approx(1.0, abs=1e-6)  # level: no torque from an even face
    assert (0, 1) in touching


# --- collision:exclude-pairs ----------------------------------------------------------------------------


def test_excluded_pair_does_not_touch(backend_name: str, backend_cls: type[Backend]) -> None:
    """Two boxes overlapping by half their width without gravity, ``b`` moving into ``a`` at 0.5 m/s: an
    excluded pair never appears in contacts() and nothing acts on either (``a`` stays put, ``b`` keeps its
    velocity); the same world without the exclusion is the control (they touch and ``a`` is pushed away)."""
    w.require(backend_cls, Capability.COLLISION_FILTER)
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0))
    b = w.box("b", (0.2, 0.2, 0.2), (0.1, 0.0, 1.0), lin_vel=(-0.5, 0.0, 0.0))
    plain = w.world("overlap", [a, b], gravity=(0.0, 0.0, 0.0), steps=50)
    excluded = dataclasses.replace(plain, excluded_pairs=(("a", "b"),))
    for world, touch in ((excluded, False), (plain, True)):
        seen = False
        with w.make_backend(backend_name, world) as sim:
            for _ in range(50):
                sim.step()
                seen = seen or any((c.a, c.b) == (0, 1) for c in sim.contacts())
            s = sim.body_states()
        moved = float(np.linalg.norm(s.pos[0] - np.asarray(a.pos)))
        assert seen is touch
        # Excluded: no force at all, so ``a`` stays to float rounding and ``b`` moves freely (exact
        # velocity, free-motion tolerance). The control: a plastic push shares b's momentum, ``a`` moves
        # at about 0.25 m/s for up to 0.5 s, far more than the 1 mm asked.
        if touch:
            assert moved > 1e-3, f"the control did not push `a`: moved {moved:.3g} m"
        else:
            assert moved < tol("free_fall", backend_name)
            assert s.lin_vel[1] == pytest.approx((-0.5, 0.0, 0.0), abs=tol("free_fall", backend_name))


# --- shape:trimesh ----------------------------------------------------------------------------------------


def test_static_triangle_mesh_keeps_its_hole(backend_name: str, backend_cls: type[Backend]) -> None:
    """A static ring (trimesh's annulus: radii 0.2 and 0.4 m, 0.1 m high, 256 triangles, centre at z 0.5)
    as a triangle mesh: a 0.05 m sphere 1 cm above the ring's top rests on it (centre at 0.6 m, the main
    suite's resting tolerance), while one dropped through the hole falls to the ground below. Built as its
    convex hull (a solid disc), the second sphere would rest on the disc at 0.6 m too."""
    w.require(backend_cls, Capability.SHAPE_COMPOUND)
    w.require(backend_cls, Capability.SHAPE_TRIMESH)
    ring = trimesh.creation.annulus(r_min=0.2, r_max=0.4, height=0.1, sections=32)
    mesh = Mesh(
        tuple((float(x), float(y), float(z)) for x, y, z in ring.vertices),
        tuple((int(a), int(b), int(c)) for a, b, c in ring.faces),
        source="annulus",
    )
    placed = PlacedShape(Shape(ShapeKind.TRIMESH, mesh=mesh))
    static = BodySpec("ring", Motion.STATIC, Shape(ShapeKind.COMPOUND), 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.5),
                      w.IDENTITY, shapes=(placed,))  # fmt: skip
    on_ring = w.sphere("on_ring", 0.05, (0.3, 0.0, 0.61), density=500.0)
    in_hole = w.sphere("in_hole", 0.05, (0.0, 0.0, 0.61), density=500.0)
    world = w.world("ring", [w.ground(), static, on_ring, in_hole])
    with w.make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    assert s.pos[2, 2] == pytest.approx(0.6, abs=tol("resting_height", backend_name))
    assert s.pos[3, 2] < 0.45 - 0.05  # below the ring's underside: through the hole
