"""The robot part of the shared backend suite (issue 22): compound bodies, COM offsets, convex hulls and
excluded pairs, checked against analytic values on every backend that declares the capability.

The worlds are built here in Python (no URDF), so each test isolates one rule of the contract text in
``backends/types.py``. Every backend declares compound shapes, COM offsets, convex hulls and excluded
pairs; ``shape:trimesh`` (ODE, DART) is checked on the others to be refused up front with the alternative
(docs/robots.md), so no test here is skipped for a missing mapping.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.special import ellipk

from backends.base import Backend
from backends.errors import UnsupportedFeature
from backends.geometry import quat_from_axis_angle, quat_rotate
from backends.testing import worlds as w
from backends.testing.tolerances import tol
from backends.testing.worlds import ZERO, G, make_backend, require
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
from runner.compile.program import build_program
from runner.language.load import load_scenario, variant_names
from runner.sim.run import run_loaded
from tests.paths import ROOT

# --- helpers --------------------------------------------------------------------------------------


def _robot_world(name: str, bodies: list[BodySpec], **kw: object) -> CompiledWorld:
    """``worlds.world`` with ``excluded_pairs`` (and any other CompiledWorld field) added."""
    excluded = kw.pop("excluded_pairs", ())
    base = w.world(name, bodies, **kw)  # type: ignore[arg-type]
    return CompiledWorld(**{**base.__dict__, "excluded_pairs": excluded})


def _compound(name: str, shapes: tuple[PlacedShape, ...], pos: Vec3, mass: float, inertia: Vec3,
              **kw: object) -> BodySpec:  # fmt: skip
    return BodySpec(name, Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), mass, inertia, pos, w.IDENTITY,
                    shapes=shapes, **kw)  # type: ignore[arg-type]  # fmt: skip


# --- shape:compound -------------------------------------------------------------------------------


def test_compound_body_rests_on_its_shapes(
    backend_name: str, backend_cls: type[Backend], request: pytest.FixtureRequest
) -> None:
    """A frame with two boxes hung 0.3 m below it at x = +-0.4: a 0.2 m cube, and a 0.2 x 0.2 x 0.4 box
    turned 90 degrees about x by its own local quaternion (so it is 0.2 m tall). Both touch the ground
    when the frame is level at 0.3 + 0.1 = 0.4 m; the second box's pose is ignored if it tilts."""
    require(backend_cls, Capability.SHAPE_COMPOUND)
    if backend_name == "pybullet":
        # The compound never comes to rest: Bullet's PGS stops once its residual is below
        # solverResidualThreshold (PyBullet's default 1e-7, not set by the adapter), which leaves this
        # contact set (8 points, 0.4 m below the COM: normal and friction rows coupled through the rotation)
        # in a period-2 cycle, v_z = +-2.97e-5 m/s and w = +-8e-5 rad/s alternating every step, forever
        # (1000 steps measured). The normal impulse alternates with it: m (g dt +- 2 v_z) / dt, i.e.
        # 1 +- 2 v_z / (g dt) = 1 +- 6.05e-4 of m*g. Not compound-specific: one box hung 0.3 m below its
        # COM cycles at +-3.0e-4. solverResidualThreshold 0 converges it (1.2e-10 of m*g at 1000 steps;
        # -1.3e-5 at step 100, still pushing out its landing), but changes every PyBullet scenario
        # (docs/backends/pybullet.md, "Robots").
        request.applymarker(pytest.mark.xfail(strict=True, reason=(
            "pybullet: the resting two-box compound cycles (v_z +-2.97e-5 m/s every other step): Bullet's PGS "
            "stops at its residual threshold 1e-7, so the normal forces sum to m*g (1 +- 6.05e-4)")))  # fmt: skip
    turned = quat_from_axis_angle((1.0, 0.0, 0.0), math.pi / 2)
    shapes = (
        PlacedShape(Shape(ShapeKind.BOX, size=(0.2, 0.2, 0.2)), pos=(0.4, 0.0, -0.3)),
        PlacedShape(Shape(ShapeKind.BOX, size=(0.2, 0.2, 0.4)), pos=(-0.4, 0.0, -0.3), quat=turned),
    )
    bar = _compound("bar", shapes, (0.0, 0.0, 0.41), 2.0, (0.1, 0.1, 0.1))
    with make_backend(backend_name, _robot_world("compound", [w.ground(), bar], steps=100)) as sim:
        for _ in range(100):
            sim.step()
        s, touching = sim.body_states(), sim.contacts()
    eps = tol("resting_height", backend_name)
    assert s.pos[1] == pytest.approx((0.0, 0.0, 0.4), abs=eps)
    assert abs(s.quat[1][0]) == pytest.approx(1.0, abs=1e-6)  # level: both boxes carry it
    assert [(c.a, c.b) for c in touching] == [(0, 1)]
    assert sum(c.normal_force for c in touching) == pytest.approx(2.0 * G, rel=tol("contact_force", backend_name))


def test_compound_mass_comes_from_the_body(backend_name: str, backend_cls: type[Backend]) -> None:
    """Mass and inertia are the body's, never the shapes': a 1 N s impulse on a 2 kg body carrying a 1 m
    cube (1,000 kg at water's density, what an engine deriving mass would use) gives 0.5 m/s; a 1 N m s
    angular impulse about z gives 1/I_z. No gravity, so nothing else acts."""
    require(backend_cls, Capability.SHAPE_COMPOUND)
    cube = (PlacedShape(Shape(ShapeKind.BOX, size=(1.0, 1.0, 1.0))),)
    dt = 0.01
    body = _compound("block", cube, (0.0, 0.0, 5.0), 2.0, (0.2, 0.3, 0.4))
    with make_backend(backend_name, _robot_world("mass", [body], gravity=ZERO, dt=dt)) as sim:
        sim.apply_force(0, (1.0 / dt, 0.0, 0.0), (0.0, 0.0, 1.0 / dt))
        sim.step()
        s = sim.body_states()
    rel = tol("inertia", backend_name)
    assert s.lin_vel[0] == pytest.approx((0.5, 0.0, 0.0), rel=rel, abs=1e-12)
    assert s.ang_vel[0] == pytest.approx((0.0, 0.0, 1.0 / 0.4), rel=rel, abs=1e-12)


def test_empty_compound_never_touches(backend_name: str, backend_cls: type[Backend]) -> None:
    """A compound body with no shapes falls through the ground as in free fall (semi-implicit Euler:
    z_n = z0 - g*dt^2*n(n+1)/2) and is never in ``contacts()``."""
    require(backend_cls, Capability.SHAPE_COMPOUND)
    dt, z0, n = 0.01, 0.5, 60
    ghost = _compound("ghost", (), (0.0, 0.0, z0), 1.0, (0.01, 0.01, 0.01))
    with make_backend(backend_name, _robot_world("ghost", [w.ground(), ghost], dt=dt)) as sim:
        for _ in range(n):
            sim.step()
            assert sim.contacts() == []
        z = sim.body_states().pos[1, 2]
    assert z == pytest.approx(z0 - G * dt * dt * n * (n + 1) / 2, abs=tol("free_fall", backend_name))


# --- body:com-offset ------------------------------------------------------------------------------

#: The physical pendulum's half period, relative. Derived for reduced-coordinate engines (the hinge
#: angle is their coordinate, stepped by semi-implicit Euler): that scheme's phase error is
#: (omega*h)^2/24 = 7e-7 at omega 4.1 rad/s, h 1 ms; the crossing of the rate through zero is
#: interpolated linearly where the rate is linear in t to third order (an extreme: theta' = 0 makes
#: alpha' = 0), a few 1e-9 s. Sum < 1e-6, bound 1e-5.
PHYSICAL_PENDULUM = {"default": 1e-5}


def _com_pendulum() -> tuple[CompiledWorld, float]:
    """A body whose frame sits on a hinge about world x at (0, 0, 1), turned 90 degrees about z, its COM at
    (0.3, 0, -0.4) in its frame, i.e. (0, 0.3, -0.4) from the anchor in the world: 0.5 m from the axis,
    released 36.87 degrees from hanging. Principal moments (0.03, 0.05, 0.07) about axes turned 30
    degrees about (1, 1, 1)/sqrt(3) from the body frame. Returns the world and the exact half period
    T/2 = 2*sqrt(I/(m*g*d))*K(sin^2(theta0/2)) (K: the complete elliptic integral of the first kind,
    parameter m = k^2), with I the moment about the axis through the anchor: the axis' moment of the
    inertia tensor about the COM (rotated into the world) plus m*d^2."""
    m, d = 2.0, 0.5
    frame = quat_from_axis_angle((0.0, 0.0, 1.0), math.pi / 2)
    axes = quat_from_axis_angle(tuple(np.ones(3) / math.sqrt(3.0)), math.pi / 6)  # type: ignore[arg-type]
    body = BodySpec("bob", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), m, (0.03, 0.05, 0.07), (0.0, 0.0, 1.0),
                    frame, com=(0.3, 0.0, -0.4), inertia_quat=axes)  # fmt: skip
    hinge = JointSpec("hinge", JointKind.HINGE, "bob", None, axis=(1.0, 0.0, 0.0), anchor=(0.0, 0.0, 1.0))
    x_body = np.array(quat_rotate((frame[0], -frame[1], -frame[2], -frame[3]), (1.0, 0.0, 0.0)))
    i_axis = float(x_body @ body.inertia_tensor() @ x_body) + m * d * d
    theta0 = math.atan2(0.3, 0.4)
    half = 2.0 * math.sqrt(i_axis / (m * G * d)) * float(ellipk(math.sin(theta0 / 2.0) ** 2))
    return _robot_world("com-pendulum", [body], joints=(hinge,), dt=0.001), half


def test_com_offset_pendulum_period(backend_name: str, backend_cls: type[Backend]) -> None:
    """The body swings as its physical pendulum (COM offset and principal axes honoured), and its frame,
    whose origin is on the axis, stays there: ``body_states`` reports the frame, not the COM."""
    require(backend_cls, Capability.COM_OFFSET)
    require(backend_cls, Capability.SHAPE_COMPOUND)
    world, half = _com_pendulum()
    dt, rate, t, crossing = world.dt, 0.0, 0.0, None
    pivot = tol("pivot_distance", backend_name)
    # the frame's origin is on the axis: reduced-coordinate engines keep it there exactly (float64 rounding);
    # ODE's hinge is a velocity constraint in maximal coordinates whose position error is corrected by ERP
    # each step, so the origin's velocity error is at most what one unconstrained step of gravity adds, g*dt
    exact = G * world.dt if backend_name == "ode" else tol("fresh_states", backend_name)
    with make_backend(backend_name, world) as sim:
        while crossing is None and t < 2.0 * half:
            sim.step()
            t += dt
            new = float(sim.joint_states().velocity[0])
            if t > dt and rate * new < 0.0:  # the rate changes sign: the other extreme
                crossing = t - dt + dt * rate / (rate - new)
            rate = new
            s = sim.body_states()
            assert s.pos[0] == pytest.approx((0.0, 0.0, 1.0), abs=pivot)
            assert s.lin_vel[0] == pytest.approx(ZERO, abs=exact)
    assert crossing is not None
    assert crossing == pytest.approx(half, rel=PHYSICAL_PENDULUM.get(backend_name, PHYSICAL_PENDULUM["default"]))


def test_force_acts_at_the_com(backend_name: str, backend_cls: type[Backend]) -> None:
    """``apply_force`` acts at the COM: a pure force on a body whose COM is 0.5 m from its frame origin
    gives no spin, and the origin moves with the COM (v = F*dt/m)."""
    require(backend_cls, Capability.COM_OFFSET)
    require(backend_cls, Capability.SHAPE_COMPOUND)
    dt, m = 0.01, 2.0
    body = BodySpec("puck", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), m, (0.1, 0.1, 0.1), (0.0, 0.0, 5.0),
                    w.IDENTITY, com=(0.5, 0.0, 0.0))  # fmt: skip
    with make_backend(backend_name, _robot_world("at-com", [body], gravity=ZERO, dt=dt)) as sim:
        sim.apply_force(0, (0.0, 2.0 / dt, 0.0), ZERO)
        sim.step()
        sim.step()
        s = sim.body_states()
    exact = tol("fresh_states", backend_name)
    assert s.ang_vel[0] == pytest.approx(ZERO, abs=exact)
    assert s.lin_vel[0] == pytest.approx((0.0, 1.0, 0.0), abs=exact)
    assert s.pos[0] == pytest.approx((0.0, 2.0 * dt, 5.0), abs=exact)


# --- shape:convex ---------------------------------------------------------------------------------


@pytest.mark.parametrize("turned", [False, True], ids=["flat", "on-its-side"])
def test_convex_hull_box_rests_at_half_height(backend_name: str, backend_cls: type[Backend], turned: bool) -> None:
    """A 0.3 x 0.2 x 0.1 box given as a hull (8 vertices, 12 triangles) rests with its centre at half its
    height: 0.05 m flat, 0.1 m turned 90 degrees about x by the body's pose."""
    require(backend_cls, Capability.SHAPE_CONVEX)
    size = (0.3, 0.2, 0.1)
    quat = quat_from_axis_angle((1.0, 0.0, 0.0), math.pi / 2) if turned else w.IDENTITY
    height = 0.1 if turned else 0.05
    mass, inertia = w.box_mass(size, 500.0)
    hull = Shape(ShapeKind.CONVEX, mesh=w.box_hull(size))
    body = BodySpec("hull", Motion.DYNAMIC, hull, mass, inertia, (0.0, 0.0, height + 0.01), quat)
    with make_backend(backend_name, _robot_world("hull", [w.ground(), body])) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    assert s.pos[1, 2] == pytest.approx(height, abs=tol("resting_height", backend_name))
    assert np.linalg.norm(s.lin_vel[1]) < 0.01


def test_thin_convex_plate_holds_a_box(backend_name: str, backend_cls: type[Backend]) -> None:
    """A static hull 1 mm thick (a plate a URDF may well hold) builds and carries a 0.1 m box resting on its
    top face: the box's centre at 0.001 + 0.05 m. No ground: only the plate holds it."""
    require(backend_cls, Capability.SHAPE_CONVEX)
    require(backend_cls, Capability.SHAPE_COMPOUND)
    plate = Shape(ShapeKind.CONVEX, mesh=w.box_hull((1.0, 1.0, 0.001)))
    static = BodySpec("plate", Motion.STATIC, Shape(ShapeKind.COMPOUND), 0.0, ZERO, ZERO, w.IDENTITY,
                      shapes=(PlacedShape(plate, pos=(0.0, 0.0, 0.0005)),))  # fmt: skip
    box = w.box("box", (0.1, 0.1, 0.1), (0.0, 0.0, 0.061), density=500.0)
    with make_backend(backend_name, _robot_world("plate", [static, box])) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    assert s.pos[1, 2] == pytest.approx(0.051, abs=tol("resting_height", backend_name))


#: A tetrahedron with a flat 0.2 m triangle for a bottom, its vertices given off the shape's origin (by OFF).
_TETRA = ((-0.1, -0.1, -0.1), (0.1, -0.1, -0.1), (0.0, 0.1, -0.1), (0.0, 0.0, 0.1))
_OFF = (0.03, 0.02, 0.05)


def test_compound_of_a_box_and_a_hull_rests_on_both(backend_name: str, backend_cls: type[Backend]) -> None:
    """A frame carrying, 0.3-0.35 m below it, a 0.2 m cube at x = +0.4 and a convex hull at x = -0.4: a
    tetrahedron whose vertices sit off its shape's origin (by _OFF) and whose shape is turned 90 degrees about
    z, both bottoms at 0.4 m below the frame (the compound PyBullet once refused: a mesh among other shapes,
    as bike.urdf's and microtaur.urdf's links). Dropped from 1 cm, it rests level with the frame at 0.4 m
    (``hull_resting_height``), on the ground alone, with contact points on the ground plane under each shape:
    under the cube's square and under the tetrahedron's triangle (its corners, turned, at (-0.3, -0.1), (-0.3, 0.1)
    and (-0.5, 0)), so each of the two shapes carries part of the weight."""
    require(backend_cls, Capability.SHAPE_COMPOUND)
    require(backend_cls, Capability.SHAPE_CONVEX)
    require(backend_cls, Capability.CONTACT_POINTS)
    turned = quat_from_axis_angle((0.0, 0.0, 1.0), math.pi / 2)
    vertices = tuple((x + _OFF[0], y + _OFF[1], z + _OFF[2]) for x, y, z in _TETRA)
    hull = Mesh(vertices=vertices, faces=((0, 2, 1), (0, 1, 3), (1, 2, 3), (2, 0, 3)), source="tetrahedron")
    back = quat_rotate(turned, _OFF)  # the shape's origin sits so that the tetrahedron's centre is at x = -0.4
    shapes = (
        PlacedShape(Shape(ShapeKind.BOX, size=(0.2, 0.2, 0.2)), pos=(0.4, 0.0, -0.3)),
        PlacedShape(Shape(ShapeKind.CONVEX, mesh=hull), pos=(-0.4 - back[0], -back[1], -0.3 - back[2]), quat=turned),
    )
    frame = _compound("frame", shapes, (0.0, 0.0, 0.41), 2.0, (0.1, 0.1, 0.1))
    world = dataclasses.replace(_robot_world("box-and-hull", [w.ground(), frame], steps=100), contact_points=True)
    with make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        s, touching, points = sim.body_states(), sim.contacts(), sim.contact_points()
    eps = tol("hull_resting_height", backend_name)
    assert s.pos[1] == pytest.approx((0.0, 0.0, 0.4), abs=eps)
    # level: each bottom within eps of the ground, 0.8 m apart, tilts it at most 2 eps / 0.8 rad: 1 - w = tilt^2 / 8
    assert abs(s.quat[1][0]) == pytest.approx(1.0, abs=(2 * eps / 0.8) ** 2 / 8)
    assert [(c.a, c.b) for c in touching] == [(0, 1)]
    assert all(abs(pt.pos[2]) <= eps for pt in points), points
    under_box = [pt for pt in points if 0.3 - eps <= pt.pos[0] <= 0.5 + eps and abs(pt.pos[1]) <= 0.1 + eps]
    under_hull = [pt for pt in points if -0.5 - eps <= pt.pos[0] <= -0.3 + eps and abs(pt.pos[1]) <= 0.1 + eps]
    assert len(under_box) + len(under_hull) == len(points), points
    assert sum(pt.force for pt in under_box) > 0 and sum(pt.force for pt in under_hull) > 0, points


# --- collision:exclude-pairs ----------------------------------------------------------------------


@pytest.mark.parametrize("excluded", [True, False], ids=["excluded", "control"])
def test_excluded_pair_does_not_push_apart(backend_name: str, backend_cls: type[Backend], excluded: bool) -> None:
    """Two 0.3 m boxes overlapping by half, with no gravity: excluded, they stay where they are and are
    never in ``contacts()``; the control (not excluded) pushes them apart, so the test can fail."""
    require(backend_cls, Capability.COLLISION_FILTER)
    a = w.box("a", w.LAB_BOX, (0.0, 0.0, 1.0), density=500.0)
    b = w.box("b", w.LAB_BOX, (0.15, 0.0, 1.0), density=500.0)
    pairs = (("a", "b"),) if excluded else ()
    world = _robot_world("overlap", [a, b], gravity=ZERO, excluded_pairs=pairs)
    touched = False
    with make_backend(backend_name, world) as sim:
        for _ in range(50):
            sim.step()
            touched = touched or bool(sim.contacts())
        s = sim.body_states()
    if excluded:
        assert not touched
        stored = max(1e-12, tol("fresh_states", backend_name))  # ODE stores positions in float32
        assert s.pos[0] == pytest.approx((0.0, 0.0, 1.0), abs=stored)
        assert s.pos[1] == pytest.approx((0.15, 0.0, 1.0), abs=stored)
    else:
        # pushed apart: penetration recovery is capped at max_correcting_vel (0.1 m/s on ODE, MuJoCo and DART,
        # docs/semantics.md), so 50 steps of 0.01 s separate them by up to 5 cm; 1 cm shows they moved.
        assert touched
        assert s.pos[1, 0] - s.pos[0, 0] > 0.15 + 0.01


def test_excluded_static_pair_keeps_other_contacts(backend_name: str, backend_cls: type[Backend]) -> None:
    """A box excluded from a static block it overlaps (a link and its robot's fixed root) falls through the
    block and still rests on the ground: an exclusion removes that pair only, even where the engine
    lumps every static body into one (MuJoCo's world body)."""
    require(backend_cls, Capability.COLLISION_FILTER)
    block = w.box("block", (1.0, 1.0, 0.5), (0.0, 0.0, 0.5), motion=Motion.STATIC)
    box = w.box("box", w.LAB_BOX, (0.0, 0.0, 0.4), density=500.0)
    world = _robot_world("through", [w.ground(), block, box], excluded_pairs=(("box", "block"),))
    with make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        s, touching = sim.body_states(), sim.contacts()
    assert s.pos[2, 2] == pytest.approx(0.15, abs=tol("resting_height", backend_name))
    assert [(c.a, c.b) for c in touching] == [(0, 2)]


# --- the robot examples end to end ----------------------------------------------------------------

ROBOT_SCENARIOS = sorted((ROOT / "scenarios" / "robots").glob("*.yaml"))
ROBOT_CASES = [(p, v) for p in ROBOT_SCENARIOS for v in variant_names(p)]


@pytest.mark.parametrize("path,variant", ROBOT_CASES, ids=[f"{p.stem}:{v}" for p, v in ROBOT_CASES])
def test_robot_scenario_passes(backend_name: str, backend_cls: type[Backend], path: Path, variant: str,
                               tmp_path: Path) -> None:  # fmt: skip
    """Each example of scenarios/robots/ passes on every backend declaring what it needs (tests/integration
    globs only the top folder); a backend lacking a capability refuses it up front instead
    (tests/language/test_robot_examples.py)."""
    loaded = load_scenario(path, variant)
    for capability in sorted(build_program(loaded).world.required_capabilities(), key=str):
        require(backend_cls, capability)
    result = run_loaded(loaded, backend_name, tmp_path)
    failed = [f"{v.name}: measured {v.measured}, expected {v.expected}" for v in result.verdicts if not v.passed]
    assert result.status == "passed", f"{result.failure or ''}\n" + "\n".join(failed)
    assert result.verdicts


def test_com_offset_reset_body_places_the_frame(backend_name: str, backend_cls: type[Backend]) -> None:
    """``reset_body`` gives the body FRAME's pose and its origin's velocity; they read back as given.

    A spinning body's origin 0.5 m from its COM moves at v_com + w x (origin - com): an adapter that set
    the COM to the frame's pose, or the COM's velocity to the origin's, reads back 0.5 m or 1 m/s off.
    Tolerance: values of order 1 stored by single-precision engines, a few float32 ulps (1.2e-7): 1e-6.
    """
    require(backend_cls, Capability.COM_OFFSET)
    require(backend_cls, Capability.SHAPE_COMPOUND)
    turn_z = (math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4))
    bob = BodySpec("bob", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), 2.0, (0.05, 0.06, 0.02), ZERO, w.IDENTITY,
                   com=(0.0, 0.0, -0.5), inertia_quat=turn_z)  # fmt: skip
    world = CompiledWorld(name="reset", gravity=ZERO, dt=0.01, substeps=1, duration=1.0, bodies=(bob,))
    with make_backend(backend_name, world) as sim:
        sim.step()
        sim.reset_body(0, (1.0, 2.0, 3.0), turn_z, (0.5, 0.0, 0.0), (0.0, 2.0, 0.0))
        s = sim.body_states()
    assert s.pos[0] == pytest.approx((1.0, 2.0, 3.0), abs=1e-6)
    assert s.quat[0] * np.sign(s.quat[0, 0]) == pytest.approx(turn_z, abs=1e-6)
    assert s.lin_vel[0] == pytest.approx((0.5, 0.0, 0.0), abs=1e-6)
    assert s.ang_vel[0] == pytest.approx((0.0, 2.0, 0.0), abs=1e-6)


# --- shape:trimesh ----------------------------------------------------------------------------------------


def test_static_triangle_mesh_keeps_its_hole(backend_name: str, backend_cls: type[Backend]) -> None:
    """A static ring (trimesh's annulus: radii 0.2 and 0.4 m, 0.1 m high, 256 triangles, centre at z 0.5)
    as a triangle mesh: a 0.05 m sphere 1 cm above the ring's top rests on it (centre at 0.6 m, the main
    suite's resting tolerance), while one dropped through the hole falls to the ground below. Built as its
    convex hull (a solid disc), the second sphere would rest on the disc at 0.6 m too."""
    require(backend_cls, Capability.SHAPE_COMPOUND)
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
    if Capability.SHAPE_TRIMESH not in backend_cls.capabilities:  # MuJoCo collides with hulls only: refused
        with pytest.raises(UnsupportedFeature, match="shape:trimesh") as refused:
            make_backend(backend_name, world).close()
        # the alternative: the installed backends that declare it (ODE, DART), else how to install one
        assert "Backends that support it: " in str(refused.value) or "Install another backend: " in str(refused.value)
        return
    with make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    assert s.pos[2, 2] == pytest.approx(0.6, abs=tol("resting_height", backend_name))
    assert s.pos[3, 2] < 0.45 - 0.05  # below the ring's underside: through the hole
