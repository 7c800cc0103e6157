"""Small CompiledWorlds built in Python for the shared backend suite, plus its helpers.

Masses and inertias follow ODE's dMassSet* formulas (backends/types.py), so the suite's analytic
expectations are ODE's. Nothing here imports an engine.
"""

from __future__ import annotations

import math

import numpy as np

from backends.base import Backend
from backends.registry import create_backend
from backends.types import (
    BodySpec,
    Capability,
    CompiledWorld,
    JointKind,
    JointSpec,
    Mesh,
    Motion,
    Motor,
    PairSurface,
    Quat,
    Shape,
    ShapeKind,
    Surface,
    Vec3,
)

G = 9.81
IDENTITY: Quat = (1.0, 0.0, 0.0, 0.0)
ZERO: Vec3 = (0.0, 0.0, 0.0)
#: The lab's box (0.3 m, density 500 -> 13.5 kg) and door (2 x 2 x 0.1, density 1000 -> 400 kg).
LAB_BOX = (0.3, 0.3, 0.3)
LAB_DOOR = (2.0, 2.0, 0.1)
#: The lab's door motor (vel 0.3 m/s, fmax 100 N) and the suite's default surface (no bounce, mu 1).
LAB_MOTOR = Motor(0.3, 100.0)
GRIPPY = Surface(bounce=0.0, mu=1.0)


def require(backend_cls: type[Backend], *capabilities: Capability) -> None:
    """Skip the calling test, saying why, when the backend does not declare each of ``capabilities``."""
    import pytest  # only under pytest: the worlds themselves do not need it

    for capability in capabilities:
        if capability not in backend_cls.capabilities:
            pytest.skip(f"backend `{backend_cls.name}` does not declare {capability.value}")


def same_rotation(q: np.ndarray, expected: tuple[float, ...]) -> np.ndarray:
    """``q`` with its sign chosen to match ``expected`` (q and -q are the same rotation)."""
    return q if float(np.dot(q, expected)) >= 0.0 else -q


def make_backend(name: str, world: CompiledWorld) -> Backend:
    """Build ``world`` on backend ``name`` through the registry (capability and option checks included)."""
    return create_backend(name, world)


# --- bodies ---------------------------------------------------------------------------------------


def box_mass(size: Vec3, density: float) -> tuple[float, Vec3]:
    """ODE dMassSetBox: m = rho*lx*ly*lz, I = m/12*(ly^2+lz^2, lx^2+lz^2, lx^2+ly^2)."""
    lx, ly, lz = size
    m = density * lx * ly * lz
    return m, (m / 12 * (ly * ly + lz * lz), m / 12 * (lx * lx + lz * lz), m / 12 * (lx * lx + ly * ly))


def sphere_mass(radius: float, density: float) -> tuple[float, Vec3]:
    """ODE dMassSetSphere: m = 4/3*pi*r^3*rho, I = 2/5*m*r^2."""
    m = 4.0 / 3.0 * math.pi * radius**3 * density
    i = 0.4 * m * radius * radius
    return m, (i, i, i)


def capsule_mass(radius: float, length: float, density: float) -> tuple[float, Vec3]:
    """ODE dMassSetCapsule along z (``length`` = the cylindrical part)."""
    m1 = math.pi * radius * radius * length * density
    m2 = 4.0 / 3.0 * math.pi * radius**3 * density
    ia = m1 * (0.25 * radius * radius + length * length / 12) + m2 * (
        0.4 * radius * radius + 0.375 * radius * length + 0.25 * length * length
    )
    ib = (0.5 * m1 + 0.4 * m2) * radius * radius
    return m1 + m2, (ia, ia, ib)


def cylinder_mass(radius: float, length: float, density: float) -> tuple[float, Vec3]:
    """ODE dMassSetCylinder along z."""
    m = math.pi * radius * radius * length * density
    ia = m * (0.25 * radius * radius + length * length / 12)
    return m, (ia, ia, 0.5 * m * radius * radius)


def body(
    name: str,
    shape: Shape,
    pos: Vec3,
    *,
    density: float = 1000.0,
    motion: Motion = Motion.DYNAMIC,
    quat: Quat = IDENTITY,
    lin_vel: Vec3 = ZERO,
    ang_vel: Vec3 = ZERO,
) -> BodySpec:
    """A body with ODE's mass for its shape (mass 0 when static)."""
    if shape.kind is ShapeKind.BOX:
        mass, inertia = box_mass(shape.size, density)
    elif shape.kind is ShapeKind.SPHERE:
        mass, inertia = sphere_mass(shape.radius, density)
    elif shape.kind is ShapeKind.CAPSULE:
        mass, inertia = capsule_mass(shape.radius, shape.length, density)
    elif shape.kind is ShapeKind.CYLINDER:
        mass, inertia = cylinder_mass(shape.radius, shape.length, density)
    else:
        mass, inertia = 0.0, ZERO
    if motion is Motion.STATIC:
        mass, inertia = 0.0, ZERO
    return BodySpec(name, motion, shape, mass, inertia, pos, quat, lin_vel, ang_vel)


def box(name: str, size: Vec3, pos: Vec3, **kw: object) -> BodySpec:
    return body(name, Shape(ShapeKind.BOX, size=size), pos, **kw)  # type: ignore[arg-type]


def sphere(name: str, radius: float, pos: Vec3, **kw: object) -> BodySpec:
    return body(name, Shape(ShapeKind.SPHERE, radius=radius), pos, **kw)  # type: ignore[arg-type]


def box_hull(size: Vec3) -> Mesh:
    """A box's 8 corners and 12 outward triangles (counter-clockwise seen from outside), for shape:convex."""
    hx, hy, hz = (s / 2.0 for s in size)
    vertices = tuple((sx * hx, sy * hy, sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1))
    # corner index = 4*(x>0) + 2*(y>0) + (z>0)
    faces = (
        (0, 1, 3), (0, 3, 2),  # -x
        (4, 6, 7), (4, 7, 5),  # +x
        (0, 4, 5), (0, 5, 1),  # -y
        (2, 3, 7), (2, 7, 6),  # +y
        (0, 2, 6), (0, 6, 4),  # -z
        (1, 5, 7), (1, 7, 3),  # +z
    )  # fmt: skip
    return Mesh(vertices=vertices, faces=faces, source="box")


def ground(name: str = "ground") -> BodySpec:
    """A static plane through the origin, normal +z."""
    return body(name, Shape(ShapeKind.PLANE), ZERO, motion=Motion.STATIC)


def world(
    name: str,
    bodies: list[BodySpec],
    *,
    joints: tuple[JointSpec, ...] = (),
    gravity: Vec3 = (0.0, 0.0, -G),
    dt: float = 0.01,
    substeps: int = 1,
    steps: int = 100,
    surface: Surface = GRIPPY,
    pairs: tuple[PairSurface, ...] = (),
) -> CompiledWorld:
    return CompiledWorld(
        name=name,
        gravity=gravity,
        dt=dt,
        substeps=substeps,
        duration=steps * dt,
        bodies=tuple(bodies),
        joints=joints,
        default_surface=surface,
        pair_surfaces=pairs,
    )


# --- the suite's worlds ---------------------------------------------------------------------------


def free_fall(z0: float = 2.0, dt: float = 0.01) -> CompiledWorld:
    return world("free-fall", [box("box", LAB_BOX, (0.0, 0.0, z0), density=500.0)], dt=dt)


def lab_kick(substeps: int = 1) -> CompiledWorld:
    """The lab's box at (1, 0, 2), no floor; the test applies 1000 N up for the first step."""
    return world("kick", [box("box", LAB_BOX, (1.0, 0.0, 2.0), density=500.0)], dt=0.04, substeps=substeps)


def spin_up(shape: Shape) -> CompiledWorld:
    """One dynamic body in zero gravity for the inertia check."""
    return world("spin-up", [body("body", shape, (0.0, 0.0, 1.0))], gravity=ZERO, dt=0.01)


def lab_door(*, lo: float | None = None, hi: float | None = None, motor: Motor | None = LAB_MOTOR) -> CompiledWorld:
    """The lab's door at (1, 0, 1) on a slider to the environment along x."""
    door = box("door", LAB_DOOR, (1.0, 0.0, 1.0), density=1000.0)
    joint = JointSpec("slider", JointKind.SLIDER, "door", None, axis=(1.0, 0.0, 0.0), lo=lo, hi=hi, motor=motor)
    return world("door", [door], joints=(joint,), dt=0.04)


def two_doors() -> CompiledWorld:
    """Two of the lab's doors, each on a slider to the environment with its motor off (along x and along y)."""
    doors = [box("door_x", LAB_DOOR, (1.0, 0.0, 1.0), density=1000.0), box("door_y", LAB_DOOR, (1.0, 5.0, 1.0),
             density=1000.0)]  # fmt: skip
    off = Motor(0.0, 0.0)
    joints = (JointSpec("slider_x", JointKind.SLIDER, "door_x", None, axis=(1.0, 0.0, 0.0), motor=off),
              JointSpec("slider_y", JointKind.SLIDER, "door_y", None, axis=(0.0, 1.0, 0.0), motor=off))  # fmt: skip
    return world("two-doors", doors, joints=joints, dt=0.04)


def offset_hinge(
    *, lo: float | None = None, hi: float | None = None, kind: JointKind = JointKind.HINGE
) -> CompiledWorld:
    """A 1 kg, 0.1 m cube whose centre is 0.5 m along +x from a hinge about +y at (0, 0, 1).

    Gravity makes it swing down, i.e. turn positively about +y.
    """
    bob = box("bob", (0.1, 0.1, 0.1), (0.5, 0.0, 1.0), density=1000.0)
    joint = JointSpec("hinge", kind, "bob", None, axis=(0.0, 1.0, 0.0), anchor=(0.0, 0.0, 1.0), lo=lo, hi=hi)
    return world("hinge", [bob], joints=(joint,), dt=0.01)


def kinematic_platform() -> CompiledWorld:
    """A 1 x 1 x 0.1 kinematic platform with a 0.2 m cube resting on it (mu 1), dt 0.01."""
    platform = box("platform", (1.0, 1.0, 0.1), (0.0, 0.0, 0.5), motion=Motion.KINEMATIC)
    cube = box("cube", (0.2, 0.2, 0.2), (0.0, 0.0, 0.65), density=500.0)
    return world("platform", [platform, cube], surface=GRIPPY)


def box_on_ground(gap: float = 0.0, gravity: Vec3 = (0.0, 0.0, -G)) -> CompiledWorld:
    """The lab's box resting on a static plane, its bottom ``gap`` metres above it."""
    cube = box("box", LAB_BOX, (0.0, 0.0, 0.15 + gap), density=500.0)
    return world("box-on-ground", [ground(), cube], gravity=gravity)


def resting_shape(shape: Shape) -> CompiledWorld:
    """A shape upright (local z up) on a plane, 1 cm above its resting height."""
    h = {
        ShapeKind.BOX: shape.size[2] / 2,
        ShapeKind.SPHERE: shape.radius,
        ShapeKind.CAPSULE: shape.length / 2 + shape.radius,
        ShapeKind.CYLINDER: shape.length / 2,
    }[shape.kind]
    return world("resting", [ground(), body("body", shape, (0.0, 0.0, h + 0.01), density=500.0)])


def bouncing_sphere(bounce: float, drop: float, dt: float = 0.001, substeps: int = 1) -> CompiledWorld:
    """A 0.1 m sphere whose bottom is ``drop`` metres above a plane; bounce_vel 0, mu 1."""
    ball = sphere("ball", 0.1, (0.0, 0.0, 0.1 + drop), density=1000.0)
    surface = Surface(bounce=bounce, bounce_vel=0.0, mu=1.0)
    return world("bounce", [ground(), ball], dt=dt, substeps=substeps, surface=surface)


def sliding_box(v0: float, mu: float) -> CompiledWorld:
    """A 0.2 m cube resting on a plane, launched along +x at ``v0`` with Coulomb ``mu``."""
    cube = box("box", (0.2, 0.2, 0.2), (0.0, 0.0, 0.1), density=500.0, lin_vel=(v0, 0.0, 0.0))
    return world("slide", [ground(), cube], surface=Surface(bounce=0.0, mu=mu))


def busy() -> CompiledWorld:
    """Boxes and a sphere falling onto a plane and onto each other, for the determinism check."""
    bodies = [ground()]
    for i in range(6):
        pos = (0.05 * (i % 2), 0.03 * (i % 3), 0.2 + 0.25 * i)
        quat = (math.cos(0.1 * i), 0.0, 0.0, math.sin(0.1 * i))
        bodies.append(box(f"box{i}", (0.2, 0.2, 0.2), pos, density=500.0, quat=quat))
    bodies.append(sphere("ball", 0.1, (0.02, 0.0, 2.0), lin_vel=(0.1, 0.0, 0.0), ang_vel=(0.0, 0.0, 3.0)))
    return world("busy", bodies, surface=Surface(bounce=0.2, mu=0.8))


def misuse(with_ball: bool = True) -> CompiledWorld:
    """One body of each kind for the edge cases: static ground, kinematic platform, a free dynamic box,
    the lab's door on a slider and (where the backend has ball joints) a bob on a ball joint."""
    bodies = [
        ground(),
        box("platform", (1.0, 1.0, 0.1), (5.0, 0.0, 0.5), motion=Motion.KINEMATIC),
        box("box", LAB_BOX, (0.0, 0.0, 2.0), density=500.0),
        box("door", LAB_DOOR, (10.0, 0.0, 1.0), density=1000.0),
    ]
    joints = [JointSpec("slider", JointKind.SLIDER, "door", None, axis=(1.0, 0.0, 0.0), motor=LAB_MOTOR)]
    if with_ball:
        bodies.append(box("bob", (0.1, 0.1, 0.1), (20.5, 0.0, 1.0)))
        joints.append(JointSpec("ball", JointKind.BALL, "bob", None, anchor=(20.0, 0.0, 1.0)))
    return world("misuse", bodies, joints=tuple(joints), gravity=(0.0, 0.0, 0.0), dt=0.01)


def resting_box(substeps: int) -> CompiledWorld:
    """The lab's box (13.5 kg) resting on a plane, dt 0.04 in ``substeps`` engine steps."""
    cube = box("box", LAB_BOX, (0.0, 0.0, 0.15), density=500.0)
    return world("resting-box", [ground(), cube], dt=0.04, substeps=substeps)


def lab_door_substeps(substeps: int) -> CompiledWorld:
    """The lab's door (400 kg) on its slider, dt 0.04 in ``substeps`` engine steps, motor off at first."""
    base = lab_door(motor=Motor(0.0, 0.0))
    return world("door-substeps", list(base.bodies), joints=base.joints, dt=0.04, substeps=substeps)


def turntable(mu: float = 1.0) -> CompiledWorld:
    """A kinematic 2 x 2 x 0.1 turntable at the origin (top at z 0.55) with a 0.2 m cube resting on it
    0.5 m from the axis (along +x), Coulomb mu; dt 0.01."""
    table = box("table", (2.0, 2.0, 0.1), (0.0, 0.0, 0.5), motion=Motion.KINEMATIC)
    cube = box("cube", (0.2, 0.2, 0.2), (0.5, 0.0, 0.65), density=500.0)
    return world("turntable", [table, cube], surface=Surface(mu=mu), dt=0.01)


def coulomb_stop(v0: float, mu: float, dt: float) -> float:
    """Distance of a box decelerating at mu*g under semi-implicit Euler (0.408 m continuous for 2, 0.5)."""
    v, x = v0, 0.0
    while True:
        v -= mu * G * dt
        if v <= 0.0:
            return x
        x += v * dt
