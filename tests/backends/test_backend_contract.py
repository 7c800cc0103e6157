"""The shared backend suite: ODE's semantics, checked against analytic values on every backend.

Each test builds a small world (tests/backends/worlds.py), steps it on a real engine and compares with
ODE's formulas; per-backend tolerances live in tests/backends/tolerances.py with their measurements.
A test that needs a capability the backend does not declare is skipped with that reason. Sections 15-17
check the edge cases the contract settles identically on every backend (the fake one included);
18-19 the substep and kinematic semantics (backends/base.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

from backends.base import Backend
from backends.errors import ContractViolation, EngineFailure, UnsupportedFeature
from backends.geometry import integrate_quat, quat_from_axis_angle, quat_rotate
from backends.registry import entry, get_backend
from backends.types import (
    Capability,
    CompiledWorld,
    JointKind,
    JointSpec,
    Motion,
    Motor,
    PairSurface,
    Precision,
    Shape,
    ShapeKind,
    Surface,
)

from . import worlds as w
from .tolerances import tol
from .worlds import ZERO, G, coulomb_stop, make_backend, require


def _same_rotation(q: np.ndarray, expected: tuple[float, ...]) -> np.ndarray:
    """``q`` with its sign chosen to match ``expected`` (q and -q are the same rotation)."""
    return q if float(np.dot(q, expected)) >= 0.0 else -q


# 1. free fall ----------------------------------------------------------------------------------------


def test_free_fall(backend_name: str) -> None:
    z0, dt, eps = 2.0, 0.01, tol("free_fall", backend_name)
    with make_backend(backend_name, w.free_fall(z0, dt)) as sim:
        for n in range(1, 41):
            sim.step()
            s = sim.body_states()
            assert s.lin_vel[0, 2] == pytest.approx(-G * n * dt, abs=eps), f"step {n}"
            assert s.pos[0, 2] == pytest.approx(z0 - G * dt * dt * n * (n + 1) / 2, abs=eps), f"step {n}"
        assert np.allclose(s.pos[0, :2], 0.0, atol=eps)
        assert np.allclose(s.ang_vel[0], 0.0, atol=eps)


def test_declared_precision_is_the_format_of_the_state(backend_name: str, backend_cls: type[Backend]) -> None:
    """An engine declares the format it keeps its state in (docs/semantics.md, Rounding): a body placed at
    coordinates that float32 cannot hold reads back exactly as stored in that format, and the registry
    (engine-free) says the same as the adapter."""
    assert backend_cls.precision is entry(backend_name).precision
    pos = (0.1, 0.2, 1.0 / 3.0)  # none is a float32: each rounds by about 1e-9 relative
    weightless = w.world("still", [w.box("box", (0.3, 0.3, 0.3), pos, density=500.0)], gravity=(0.0, 0.0, 0.0))
    with make_backend(backend_name, weightless) as sim:
        sim.step()  # nothing moves it
        read = tuple(float(x) for x in sim.body_states().pos[0])
    stored = pos if backend_cls.precision is Precision.FLOAT64 else tuple(float(np.float32(x)) for x in pos)
    assert read == stored
    assert Precision.FLOAT32.eps == 2.0**-23 == float(np.finfo(np.float32).eps)
    assert Precision.FLOAT64.eps == 2.0**-52 == float(np.finfo(np.float64).eps)


# 2. one-step force -----------------------------------------------------------------------------------


@pytest.mark.parametrize("substeps", [1, 10])
def test_one_step_force(backend_name: str, backend_cls: type[Backend], substeps: int) -> None:
    if substeps > 1:
        require(backend_cls, Capability.SUBSTEPS)
    world = w.lab_kick(substeps)
    m, dt = world.bodies[0].mass, world.dt
    assert m == pytest.approx(13.5)
    v1 = 1000.0 * dt / m - G * dt  # 2.5706: the impulse acts for exactly one step
    v2 = v1 - G * dt  # 2.1782: then it is cleared
    with make_backend(backend_name, world) as sim:
        sim.apply_force(0, (0.0, 0.0, 1000.0), ZERO)
        sim.step()
        got1 = sim.body_states().lin_vel[0, 2]
        sim.step()
        got2 = sim.body_states().lin_vel[0, 2]
    eps = tol("one_step_force", backend_name)
    assert got1 == pytest.approx(2.5706, abs=eps) and got1 == pytest.approx(v1, abs=eps)
    assert got2 == pytest.approx(2.1782, abs=eps) and got2 == pytest.approx(v2, abs=eps)


@pytest.mark.parametrize("substeps", [1, 4])
def test_a_force_given_before_every_step_is_held_on_every_substep(
    backend_name: str, backend_cls: type[Backend], substeps: int
) -> None:
    """A held force (the runner's `apply`, docs/semantics.md "Held forces") is the same apply_force before
    every step: each engine step of h = dt/substeps feels it, so the acceleration a = F/m - g is constant and
    semi-implicit Euler gives, after n engine steps, exactly v = a n h and z = z0 + a h^2 n (n + 1)/2. The
    tolerance is free fall's (the same two operations per step); a torque held alongside spins the box up
    at tau/I: omega = tau/I n h (its inertia about z, 0.2025 kg m^2)."""
    if substeps > 1:
        require(backend_cls, Capability.SUBSTEPS)
    world = w.lab_kick(substeps)
    m, dt, z0 = world.bodies[0].mass, world.dt, world.bodies[0].pos[2]
    force, tau = 300.0, 0.5
    a, h, inertia = force / m - G, dt / substeps, world.bodies[0].inertia[2]
    eps = tol("free_fall", backend_name)
    with make_backend(backend_name, world) as sim:
        for k in range(1, 11):
            sim.apply_force(0, (0.0, 0.0, force), (0.0, 0.0, tau))
            sim.step()
            s = sim.body_states()
            n = k * substeps
            assert s.lin_vel[0, 2] == pytest.approx(a * n * h, abs=eps), f"step {k}"
            assert s.pos[0, 2] == pytest.approx(z0 + a * h * h * n * (n + 1) / 2, abs=eps), f"step {k}"
            assert s.ang_vel[0, 2] == pytest.approx(tau / inertia * n * h, rel=tol("inertia", backend_name))
        sim.step()  # not given again: gone
        assert sim.body_states().lin_vel[0, 2] == pytest.approx(a * 10 * dt - G * dt, abs=eps)


# 3. inertia ------------------------------------------------------------------------------------------

_SPIN_SHAPES = {
    "box": (Shape(ShapeKind.BOX, size=(0.2, 0.4, 0.6)), w.IDENTITY),
    "rotated-box": (Shape(ShapeKind.BOX, size=(0.2, 0.4, 0.6)), quat_from_axis_angle((0.0, 0.0, 1.0), 0.5)),
    "sphere": (Shape(ShapeKind.SPHERE, radius=0.1), w.IDENTITY),
}


@pytest.mark.parametrize("shape_name", list(_SPIN_SHAPES))
def test_inertia(backend_name: str, shape_name: str) -> None:
    shape, quat = _SPIN_SHAPES[shape_name]
    base = w.spin_up(shape)
    spec = base.bodies[0]
    world = w.world("spin-up", [w.body("body", shape, spec.pos, quat=quat)], gravity=ZERO, dt=base.dt)
    tau = np.array([0.3, 0.2, 0.1])
    # Expected world-frame omega = R diag(1/I) R^T tau dt, I from ODE's formulas.
    local_tau = quat_rotate((quat[0], -quat[1], -quat[2], -quat[3]), tau)
    local_w = np.array(local_tau) / np.array(world.bodies[0].inertia) * world.dt
    expected = np.array(quat_rotate(quat, local_w))
    rel = tol("inertia", backend_name)
    with make_backend(backend_name, world) as sim:
        sim.apply_force(0, ZERO, tuple(tau))  # type: ignore[arg-type]
        sim.step()
        got = sim.body_states().ang_vel[0]
        assert got == pytest.approx(expected, rel=rel, abs=1e-12)
        if shape_name == "sphere":  # isotropic: omega stays constant once the torque is cleared
            sim.step()
            assert sim.body_states().ang_vel[0] == pytest.approx(expected, rel=rel, abs=1e-12)


# 4. slider motor -------------------------------------------------------------------------------------


def _require_joint(backend_cls: type[Backend], *caps: Capability) -> None:
    for cap in caps:
        require(backend_cls, cap)


def test_slider_motor(backend_name: str, backend_cls: type[Backend]) -> None:
    _require_joint(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR)
    world = w.lab_door()
    m, dt, fmax = world.bodies[0].mass, world.dt, 100.0
    assert m == pytest.approx(400.0)
    a = fmax / m  # 0.25 m/s^2: ODE's velocity motor accelerates at fmax/m until it reaches vel
    rel, frel, idle = (tol(c, backend_name) for c in ("motor_velocity", "motor_force", "motor_force_idle"))
    v_exp = x_exp = 0.0
    seen: dict[int, float] = {}
    with make_backend(backend_name, world) as sim:
        js, exact = sim.joint_states(), tol("fresh_states", backend_name)
        assert js.position[0] == pytest.approx(0.0, abs=exact)
        assert js.velocity[0] == pytest.approx(0.0, abs=exact)
        for k in range(1, 46):
            sim.step()
            v_exp = min(0.3, v_exp + a * dt)
            x_exp += v_exp * dt
            js, bs = sim.joint_states(), sim.body_states()
            seen[k] = float(js.velocity[0])
            assert js.velocity[0] == pytest.approx(v_exp, rel=rel, abs=1e-6), f"step {k}"
            assert bs.lin_vel[0, 0] == pytest.approx(js.velocity[0], abs=1e-6), f"step {k}"
            assert js.position[0] == pytest.approx(x_exp, rel=rel, abs=1e-6), f"step {k}"
            assert js.position[0] == pytest.approx(bs.pos[0, 0] - 1.0, abs=1e-6), f"step {k}"
            if k <= 29:
                assert js.motor_force[0] == pytest.approx(fmax, rel=frel), f"step {k}"
            elif k >= 32:
                assert abs(js.motor_force[0]) <= idle, f"step {k}"
        # The lab's figures at t = 0.04, 0.4, 1.0, 1.2 s.
        for k, v in ((1, 0.0100), (10, 0.1000), (25, 0.2500), (30, 0.3000)):
            assert seen[k] == pytest.approx(v, rel=rel), f"t = {k * dt:.2f}"
        sim.set_motor(0, -0.3, fmax)  # reverse mid-run: decelerates at fmax/m again
        for k in range(1, 11):
            sim.step()
            v_exp = max(-0.3, v_exp - a * dt)
            js = sim.joint_states()
            assert js.velocity[0] == pytest.approx(v_exp, rel=rel, abs=1e-6), f"after set_motor, step {k}"
            assert js.motor_force[0] == pytest.approx(-fmax, rel=frel), f"after set_motor, step {k}"


# 5. joint stops and a passive hinge ------------------------------------------------------------------


def test_slider_stop(backend_name: str, backend_cls: type[Backend]) -> None:
    _require_joint(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR, Capability.JOINT_LIMITS)
    with make_backend(backend_name, w.lab_door(lo=-0.1, hi=0.1)) as sim:
        for _ in range(75):  # 3 s: the motor reaches the stop at about 0.9 s and keeps pushing
            sim.step()
        js, bs = sim.joint_states(), sim.body_states()
    eps = tol("slider_stop", backend_name)
    assert js.position[0] == pytest.approx(0.1, abs=eps)
    assert bs.pos[0, 0] == pytest.approx(1.1, abs=eps)
    assert abs(js.velocity[0]) < 0.01


def _bob_angle(pos: np.ndarray) -> float:
    """The offset hinge's angle about +y read from the bob's centre (0.5 m from the anchor)."""
    return math.atan2(1.0 - pos[2], pos[0])


def test_hinge_stop(backend_name: str, backend_cls: type[Backend]) -> None:
    _require_joint(backend_cls, Capability.JOINT_HINGE, Capability.JOINT_LIMITS)
    stop = math.pi / 6
    with make_backend(backend_name, w.offset_hinge(lo=-stop, hi=stop)) as sim:
        assert sim.joint_states().position[0] == pytest.approx(0.0, abs=tol("fresh_states", backend_name))
        for _ in range(200):
            sim.step()
        js, bs = sim.joint_states(), sim.body_states()
    eps = tol("hinge_stop", backend_name)
    assert js.position[0] == pytest.approx(stop, abs=eps)  # 0.5236
    assert _bob_angle(bs.pos[0]) == pytest.approx(stop, abs=eps)
    assert math.hypot(bs.pos[0, 0], 1.0 - bs.pos[0, 2]) == pytest.approx(0.5, abs=tol("pivot_distance", backend_name))


def _pendulum_reference(world_dt: float, steps: int) -> tuple[float, float]:
    """Angle and rate of the offset-hinge bob (1 kg, 0.1 m cube, r = 0.5 m) by semi-implicit Euler."""
    m, r = 1.0, 0.5
    i_anchor = m * (0.1**2 + 0.1**2) / 12 + m * r * r
    theta = omega = 0.0
    for _ in range(steps):
        omega += m * G * r * math.cos(theta) / i_anchor * world_dt
        theta += omega * world_dt
    return theta, omega


@pytest.mark.parametrize("kind", [JointKind.HINGE, JointKind.BALL], ids=["hinge", "ball"])
def test_passive_pendulum(backend_name: str, backend_cls: type[Backend], kind: JointKind) -> None:
    """No motor and no stops: the bob swings freely (PyBullet's default motor must be off)."""
    require(backend_cls, Capability(f"joint:{kind.value}"))
    world = w.offset_hinge(kind=kind)
    theta, omega = _pendulum_reference(world.dt, 30)  # 0.3 s: about 0.87 rad
    rel = tol("pendulum", backend_name)
    with make_backend(backend_name, world) as sim:
        for _ in range(30):
            sim.step()
        js, bs = sim.joint_states(), sim.body_states()
    assert _bob_angle(bs.pos[0]) == pytest.approx(theta, rel=rel)
    assert math.hypot(bs.pos[0, 0], 1.0 - bs.pos[0, 2]) == pytest.approx(0.5, abs=tol("pivot_distance", backend_name))
    assert bs.ang_vel[0] == pytest.approx((0.0, omega, 0.0), rel=rel, abs=rel * abs(omega))
    q = _same_rotation(bs.quat[0], quat_from_axis_angle((0.0, 1.0, 0.0), theta))
    assert q == pytest.approx(quat_from_axis_angle((0.0, 1.0, 0.0), theta), abs=rel * theta)
    if kind is JointKind.HINGE:
        assert js.position[0] == pytest.approx(theta, rel=rel)
        assert js.velocity[0] == pytest.approx(omega, rel=rel)
    else:
        assert math.isnan(js.position[0]) and math.isnan(js.velocity[0])


def test_fixed_joint_holds(backend_name: str, backend_cls: type[Backend]) -> None:
    require(backend_cls, Capability.JOINT_FIXED)
    with make_backend(backend_name, w.offset_hinge(kind=JointKind.FIXED)) as sim:
        for _ in range(50):
            sim.step()
        js, bs = sim.joint_states(), sim.body_states()
    assert bs.pos[0] == pytest.approx((0.5, 0.0, 1.0), abs=tol("joint_hold", backend_name))
    assert math.isnan(js.position[0])


# joints between two bodies (zero gravity: the analytic answer is two-body momentum exchange) -----------


def _two_boxes(joint: JointSpec, size_b: tuple[float, float, float] = (0.2, 0.2, 0.2)) -> CompiledWorld:
    """Box a (0.2 m, 8 kg) at (0, 0, 1) and a 4 kg box b beside it along x (slider) or on top of it."""
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0), density=1000.0)
    b_pos = (0.3, 0.0, 1.0) if joint.kind is JointKind.SLIDER else (0.0, 0.0, 1.2)
    b = w.box("b", size_b, b_pos, density=4.0 / (size_b[0] * size_b[1] * size_b[2]))
    return w.world("two-boxes", [a, b], joints=(joint,), gravity=ZERO, dt=0.01)


def test_slider_between_bodies(backend_name: str, backend_cls: type[Backend]) -> None:
    caps = (Capability.JOINT_SLIDER, Capability.JOINT_MOTOR, Capability.JOINT_BETWEEN_BODIES)
    _require_joint(backend_cls, *caps)
    joint = JointSpec("slide", JointKind.SLIDER, "b", "a", axis=(1.0, 0.0, 0.0), motor=Motor(0.3, 2.0))
    world = _two_boxes(joint)
    ma, mb = world.bodies[0].mass, world.bodies[1].mass  # 8 kg, 4 kg
    rate = 2.0 * (1.0 / ma + 1.0 / mb) * world.dt  # relative acceleration fmax*(1/ma + 1/mb) = 0.75 m/s^2
    rel = tol("motor_velocity", backend_name)
    v_exp = 0.0
    with make_backend(backend_name, world) as sim:
        for k in range(1, 51):
            sim.step()
            v_exp = min(0.3, v_exp + rate)
            js, bs = sim.joint_states(), sim.body_states()
            assert js.velocity[0] == pytest.approx(v_exp, rel=rel, abs=1e-6), f"step {k}"
            assert bs.lin_vel[1, 0] - bs.lin_vel[0, 0] == pytest.approx(js.velocity[0], abs=1e-6)
            assert js.position[0] == pytest.approx(bs.pos[1, 0] - bs.pos[0, 0] - 0.3, abs=1e-6)
            assert ma * bs.lin_vel[0, 0] + mb * bs.lin_vel[1, 0] == pytest.approx(0.0, abs=1e-6)


def test_hinge_between_bodies(backend_name: str, backend_cls: type[Backend]) -> None:
    caps = (Capability.JOINT_HINGE, Capability.JOINT_MOTOR, Capability.JOINT_BETWEEN_BODIES)
    _require_joint(backend_cls, *caps)
    joint = JointSpec(
        "turn", JointKind.HINGE, "b", "a", axis=(0.0, 0.0, 1.0), anchor=(0.0, 0.0, 1.1), motor=Motor(1.0, 0.1)
    )
    world = _two_boxes(joint, size_b=(0.4, 0.1, 0.1))  # both centres on the hinge axis
    ia, ib = world.bodies[0].inertia[2], world.bodies[1].inertia[2]
    rate = 0.1 * (1.0 / ia + 1.0 / ib) * world.dt  # about 3.64 rad/s^2
    rel = tol("motor_velocity", backend_name)
    w_exp = angle = 0.0
    with make_backend(backend_name, world) as sim:
        for k in range(1, 41):
            sim.step()
            w_exp = min(1.0, w_exp + rate)
            angle += w_exp * world.dt
            js, bs = sim.joint_states(), sim.body_states()
            assert js.velocity[0] == pytest.approx(w_exp, rel=rel, abs=1e-6), f"step {k}"
            assert js.position[0] == pytest.approx(angle, rel=rel, abs=1e-6), f"step {k}"
            assert bs.ang_vel[1, 2] - bs.ang_vel[0, 2] == pytest.approx(js.velocity[0], abs=1e-6)
            assert ia * bs.ang_vel[0, 2] + ib * bs.ang_vel[1, 2] == pytest.approx(0.0, abs=1e-6)
        assert bs.pos[:, :2] == pytest.approx(np.zeros((2, 2)), abs=1e-6)


def test_fixed_between_bodies(backend_name: str, backend_cls: type[Backend]) -> None:
    _require_joint(backend_cls, Capability.JOINT_FIXED, Capability.JOINT_BETWEEN_BODIES)
    world = _two_boxes(JointSpec("glue", JointKind.FIXED, "b", "a"))
    total = world.bodies[0].mass + world.bodies[1].mass  # 12 kg
    with make_backend(backend_name, world) as sim:
        sim.apply_force(0, (0.0, 0.0, 120.0), ZERO)  # on a only: both move at F*dt/(ma + mb)
        for _ in range(20):
            sim.step()
        bs = sim.body_states()
    v = 120.0 * world.dt / total
    assert bs.lin_vel[:, 2] == pytest.approx([v, v], rel=tol("motor_velocity", backend_name))
    assert bs.pos[1] - bs.pos[0] == pytest.approx((0.0, 0.0, 0.2), abs=tol("joint_hold", backend_name))


# 6. kinematic bodies ---------------------------------------------------------------------------------


def test_kinematic_platform(backend_name: str, backend_cls: type[Backend]) -> None:
    require(backend_cls, Capability.KINEMATIC)
    world = w.kinematic_platform()
    dt, v, exact = world.dt, 0.3, tol("kinematic_pose", backend_name)
    with make_backend(backend_name, world) as sim:
        for k in range(100):  # 1 s at 0.3 m/s, placed and given its velocity every step as the runner does
            sim.set_kinematic(0, (v * k * dt, 0.0, 0.5), w.IDENTITY, (v, 0.0, 0.0), ZERO)
            sim.step()
            s = sim.body_states()
            assert s.pos[0] == pytest.approx((v * (k + 1) * dt, 0.0, 0.5), abs=exact), f"step {k + 1}"
    assert s.pos[0, 0] == pytest.approx(0.3, abs=exact)
    assert s.lin_vel[0] == pytest.approx((v, 0.0, 0.0), abs=exact)
    assert s.pos[1, 0] == pytest.approx(0.3, rel=tol("kinematic_carry", backend_name))  # carried by friction


def test_kinematic_keeps_velocity(backend_name: str, backend_cls: type[Backend]) -> None:
    """Set once: the body moves with that linear and angular velocity, exactly, until set again."""
    require(backend_cls, Capability.KINEMATIC)
    world = w.kinematic_platform()
    lin, ang = (0.1, -0.2, 0.05), (0.2, 0.0, 0.5)
    quat = quat_from_axis_angle((1.0, 0.0, 0.0), 0.3)
    exact = tol("kinematic_pose", backend_name)
    with make_backend(backend_name, world) as sim:
        sim.set_kinematic(0, (0.0, 0.0, 0.5), quat, lin, ang)
        expected_q = quat
        for k in range(1, 11):
            sim.step()
            expected_q = integrate_quat(expected_q, ang, world.dt)
            s = sim.body_states()
            pos = tuple(0.5 * (i == 2) + lin[i] * k * world.dt for i in range(3))
            assert s.pos[0] == pytest.approx(pos, abs=exact), f"step {k}"
            assert _same_rotation(s.quat[0], expected_q) == pytest.approx(expected_q, abs=exact), f"step {k}"
            assert s.lin_vel[0] == pytest.approx(lin, abs=exact)
            assert s.ang_vel[0] == pytest.approx(ang, abs=exact)


# 7. contacts -----------------------------------------------------------------------------------------


def test_contact_resting(backend_name: str) -> None:
    world = w.box_on_ground()
    with make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        contacts = sim.contacts()
    assert len(contacts) == 1, contacts
    c = contacts[0]
    assert (c.a, c.b) == (0, 1)
    assert c.points >= 1 and c.depth >= 0.0
    if not math.isnan(c.normal_force):
        weight = world.bodies[1].mass * G
        assert c.normal_force == pytest.approx(weight, rel=tol("contact_force", backend_name))


def test_no_contact_above_plane(backend_name: str) -> None:
    """A box 1 cm above the plane touches nothing (engines that report near points must filter them)."""
    with make_backend(backend_name, w.box_on_ground(gap=0.01, gravity=ZERO)) as sim:
        for _ in range(3):
            sim.step()
            assert sim.contacts() == []


# 8. resting height -----------------------------------------------------------------------------------

_REST_SHAPES = {
    "box": (Shape(ShapeKind.BOX, size=w.LAB_BOX), 0.15),
    "sphere": (Shape(ShapeKind.SPHERE, radius=0.1), 0.1),
    "capsule": (Shape(ShapeKind.CAPSULE, radius=0.05, length=0.2), 0.15),  # ODE: length is the cylinder part
    "cylinder": (Shape(ShapeKind.CYLINDER, radius=0.1, length=0.2), 0.1),
}


@pytest.mark.parametrize("shape_name", list(_REST_SHAPES))
def test_resting_height(backend_name: str, backend_cls: type[Backend], shape_name: str) -> None:
    shape, height = _REST_SHAPES[shape_name]
    require(backend_cls, Capability(f"shape:{shape.kind.value}"))
    with make_backend(backend_name, w.resting_shape(shape)) as sim:
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    assert s.pos[1, 2] == pytest.approx(height, abs=tol("resting_height", backend_name))
    assert np.linalg.norm(s.lin_vel[1]) < 0.01


# 9. reset_body ---------------------------------------------------------------------------------------


def test_reset_body(backend_name: str) -> None:
    world = w.free_fall(dt=0.01)
    dt = world.dt
    pos, quat = (1.0, 2.0, 3.0), quat_from_axis_angle((0.0, 0.0, 1.0), math.pi / 2)
    lin, ang = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)
    with make_backend(backend_name, world) as sim:
        for _ in range(5):
            sim.step()
        sim.reset_body(0, pos, quat, lin, ang)
        s, exact = sim.body_states(), tol("fresh_states", backend_name)
        assert s.pos[0] == pytest.approx(pos, abs=exact) and s.quat[0] == pytest.approx(quat, abs=exact)
        assert s.lin_vel[0] == pytest.approx(lin, abs=exact) and s.ang_vel[0] == pytest.approx(ang, abs=exact)
        sim.step()
        s = sim.body_states()
    eps = tol("free_fall", backend_name)
    assert s.pos[0] == pytest.approx((1.0 + dt, 2.0, 3.0 - G * dt * dt), abs=eps)
    assert s.lin_vel[0] == pytest.approx((1.0, 0.0, -G * dt), abs=eps)
    expected_q = integrate_quat(quat, ang, dt)
    eps = tol("orientation", backend_name)
    assert _same_rotation(s.quat[0], expected_q) == pytest.approx(expected_q, abs=eps)


# 10. orientation convention --------------------------------------------------------------------------


def test_orientation_convention(backend_name: str) -> None:
    spin, steps = 2.0, 50
    cube = w.box("cube", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0), ang_vel=(0.0, 0.0, spin))
    world = w.world("spin", [cube], gravity=ZERO, dt=0.01)
    with make_backend(backend_name, world) as sim:
        for _ in range(steps):
            sim.step()
        s = sim.body_states()
    t = steps * world.dt
    expected = (math.cos(spin * t / 2), 0.0, 0.0, math.sin(spin * t / 2))  # (w, x, y, z)
    eps = tol("orientation", backend_name)
    assert _same_rotation(s.quat[0], expected) == pytest.approx(expected, abs=eps)
    assert s.ang_vel[0] == pytest.approx((0.0, 0.0, spin), abs=eps)
    assert s.pos[0] == pytest.approx((0.0, 0.0, 1.0), abs=eps)


# 11. restitution -------------------------------------------------------------------------------------


def test_restitution(backend_name: str, backend_cls: type[Backend]) -> None:
    require(backend_cls, Capability.CONTACT_BOUNCE)
    drop, bounce = 0.5, 0.5
    world = w.bouncing_sphere(bounce, drop, dt=0.001)
    apex, rising = -math.inf, False
    with make_backend(backend_name, world) as sim:
        for _ in range(900):
            sim.step()
            s = sim.body_states()
            if s.lin_vel[1, 2] > 0.0:
                rising = True
            if rising:
                apex = max(apex, float(s.pos[1, 2]))
                if s.lin_vel[1, 2] < 0.0:
                    break
    ratio = (apex - 0.1) / drop
    assert rising, "the sphere never rebounded"
    assert ratio == pytest.approx(bounce**2, abs=tol("restitution", backend_name)), f"apex ratio {ratio:.4f}"


def test_bouncy_surface_rests(backend_name: str, backend_cls: type[Backend]) -> None:
    """A box resting on a bouncy surface (bounce 0.2, bounce_vel 0) at the lab's dt 0.04 stays still:
    ODE bounces on the approach speed before the step, which is 0 at rest, not on one step of gravity."""
    require(backend_cls, Capability.CONTACT_BOUNCE)
    cube = w.box("box", w.LAB_BOX, (0.0, 0.0, 0.15), density=500.0)
    world = w.world("bouncy-rest", [w.ground(), cube], dt=0.04, surface=Surface(bounce=0.2, mu=5000.0))
    peak = 0.0
    with make_backend(backend_name, world) as sim:
        for k in range(75):
            sim.step()
            if k >= 25:
                peak = max(peak, float(np.abs(sim.body_states().lin_vel[1]).max()))
        s = sim.body_states()
    assert peak < tol("rest_jitter", backend_name)
    assert s.pos[1, 2] == pytest.approx(0.15, abs=tol("resting_height", backend_name))


# 12. friction ----------------------------------------------------------------------------------------


def test_friction_stop_distance(backend_name: str) -> None:
    v0, mu = 2.0, 0.5
    world = w.sliding_box(v0, mu)
    with make_backend(backend_name, world) as sim:
        for _ in range(60):  # stops at 0.41 s
            sim.step()
        s = sim.body_states()
    expected = coulomb_stop(v0, mu, world.dt)
    assert s.pos[1, 0] == pytest.approx(expected, rel=tol("friction_stop", backend_name))
    assert abs(s.lin_vel[1, 0]) < 1e-3


def test_pair_surfaces(backend_name: str) -> None:
    """Per-pair mu overrides the default: two boxes slide different distances on the same plane."""
    v0 = 2.0
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 0.1), density=500.0, lin_vel=(v0, 0.0, 0.0))
    b = w.box("b", (0.2, 0.2, 0.2), (0.0, 1.0, 0.1), density=500.0, lin_vel=(v0, 0.0, 0.0))
    pairs = (PairSurface("ground", "a", Surface(mu=0.8)), PairSurface("b", "ground", Surface(mu=0.25)))
    world = w.world("pairs", [w.ground(), a, b], surface=Surface(mu=0.5), pairs=pairs)
    try:
        sim = make_backend(backend_name, world)
    except UnsupportedFeature as refusal:  # per-geometry friction (drake): refused up front, naming the pair
        assert "`ground`-`a`" in str(refusal) or "`b`-`ground`" in str(refusal) or "`a`-`b`" in str(refusal)
        pytest.skip(f"refused up front: {refusal}")
    with sim:
        for _ in range(100):  # b stops at 0.82 s
            sim.step()
        s = sim.body_states()
    rel = tol("friction_stop", backend_name)
    assert s.pos[1, 0] == pytest.approx(coulomb_stop(v0, 0.8, world.dt), rel=rel)
    assert s.pos[2, 0] == pytest.approx(coulomb_stop(v0, 0.25, world.dt), rel=rel)


def test_tilted_plane(backend_name: str) -> None:
    """A plane's normal is its local +z: a cube on a 30 degree plane (mu 0.2) slides at g(sin - mu cos)."""
    tilt = math.radians(30.0)
    q = quat_from_axis_angle((0.0, 1.0, 0.0), tilt)  # normal (sin, 0, cos): downhill is +x
    normal = np.array([math.sin(tilt), 0.0, math.cos(tilt)])
    downhill = np.array([math.cos(tilt), 0.0, -math.sin(tilt)])
    plane = w.body("ramp", Shape(ShapeKind.PLANE), ZERO, motion=Motion.STATIC, quat=q)
    cube = w.box("cube", (0.2, 0.2, 0.2), tuple(0.1 * normal), density=500.0, quat=q)
    world = w.world("ramp", [plane, cube], surface=Surface(mu=0.2))
    with make_backend(backend_name, world) as sim:
        for _ in range(50):
            sim.step()
        s = sim.body_states()
    a = G * (math.sin(tilt) - 0.2 * math.cos(tilt))  # 3.206 m/s^2
    assert float(s.lin_vel[1] @ downhill) == pytest.approx(a * 0.5, rel=tol("friction", backend_name))
    assert float(s.pos[1] @ normal) == pytest.approx(0.1, abs=tol("resting_height", backend_name))


# 13. determinism -------------------------------------------------------------------------------------


def test_determinism(backend_name: str) -> None:
    """Two fresh instances, alive and stepped side by side, agree bit for bit."""
    world = w.busy()
    if Capability.CONTACT_BOUNCE not in get_backend(backend_name).capabilities:  # the same world without bounce
        world = replace(world, default_surface=replace(world.default_surface, bounce=0.0),
                        pair_surfaces=tuple(replace(p, surface=replace(p.surface, bounce=0.0))
                                            for p in world.pair_surfaces))  # fmt: skip
    with make_backend(backend_name, world) as one, make_backend(backend_name, world) as two:
        for _ in range(150):
            one.step()
            two.step()
        s1, s2 = one.body_states(), two.body_states()
        for field in ("pos", "quat", "lin_vel", "ang_vel"):
            assert np.array_equal(getattr(s1, field), getattr(s2, field)), field
        c1 = one.contacts()
        assert c1 == two.contacts()
    assert len(c1) >= 3  # the check is not vacuous: boxes touch the plane and each other


# 14. fresh states ------------------------------------------------------------------------------------


def test_states_fresh(backend_name: str) -> None:
    z0, dt = 2.0, 0.04
    with make_backend(backend_name, w.free_fall(z0, dt)) as sim:
        assert sim.body_states().pos[0, 2] == pytest.approx(z0, abs=tol("fresh_states", backend_name))
        sim.step()
        s = sim.body_states()
    eps = tol("fresh_states", backend_name)
    assert s.pos[0, 2] - z0 == pytest.approx(-G * dt * dt, abs=eps)  # not 0: the pose after the step
    assert s.lin_vel[0, 2] == pytest.approx(-G * dt, abs=eps)


def test_joint_states_fresh(backend_name: str, backend_cls: type[Backend]) -> None:
    _require_joint(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR)
    with make_backend(backend_name, w.lab_door()) as sim:
        sim.step()
        js, bs = sim.joint_states(), sim.body_states()
    eps = tol("fresh_states", backend_name)
    assert js.position[0] == pytest.approx(0.0004, abs=eps)  # 0.01 m/s for 0.04 s
    assert bs.pos[0, 0] == pytest.approx(1.0004, abs=eps)  # PyBullet's link pitfall lags at 1.0000


def test_static_and_kinematic_bodies_report_states(backend_name: str, backend_cls: type[Backend]) -> None:
    require(backend_cls, Capability.KINEMATIC)
    with make_backend(backend_name, w.kinematic_platform()) as sim:
        sim.step()
        s = sim.body_states()
    assert s.pos.shape == (2, 3) and s.quat.shape == (2, 4)
    exact = tol("fresh_states", backend_name)
    assert s.pos[0] == pytest.approx((0.0, 0.0, 0.5), abs=exact)
    assert s.quat[0] == pytest.approx(w.IDENTITY, abs=exact)
    assert np.all(np.isfinite(s.lin_vel)) and np.all(np.isfinite(s.ang_vel))


# 15. edge cases: misuse and unknown indices ----------------------------------------------------------
# Indices in w.misuse(): bodies 0 ground (static), 1 platform (kinematic), 2 box (dynamic, free), 3 door
# (dynamic, on the slider), 4 bob (on the ball joint); joints 0 slider (with a motor), 1 ball.

_POSE = ((0.0, 0.0, 3.0), w.IDENTITY, ZERO, ZERO)
_MISUSE: dict[str, Callable[[Backend], object]] = {
    "set_kinematic on a dynamic body": lambda sim: sim.set_kinematic(2, *_POSE),
    "set_kinematic on a static body": lambda sim: sim.set_kinematic(0, *_POSE),
    "set_kinematic on a jointed body": lambda sim: sim.set_kinematic(3, *_POSE),
    "reset_body on a kinematic body": lambda sim: sim.reset_body(1, *_POSE),
    "reset_body on a static body": lambda sim: sim.reset_body(0, *_POSE),
    "reset_body on a jointed body": lambda sim: sim.reset_body(3, *_POSE),
    "body index past the end": lambda sim: sim.reset_body(len(sim.world.bodies), *_POSE),
    "negative body index": lambda sim: sim.apply_force(-1, (1.0, 0.0, 0.0), ZERO),
    "body index that is a float": lambda sim: sim.set_kinematic(1.0, *_POSE),  # type: ignore[arg-type]
    "body index that is a bool": lambda sim: sim.apply_force(True, (1.0, 0.0, 0.0), ZERO),
    "joint index past the end": lambda sim: sim.set_motor(len(sim.world.joints), 0.1, 1.0),
    "negative joint index": lambda sim: sim.set_motor(-1, 0.1, 1.0),
    "set_motor with a negative fmax": lambda sim: sim.set_motor(0, 0.1, -1.0),
    "set_motor with a NaN vel": lambda sim: sim.set_motor(0, math.nan, 1.0),
}


def _misuse_world(name: str) -> CompiledWorld:
    return w.misuse(with_ball=Capability.JOINT_BALL in get_backend(name).capabilities)


def _refused_and_unchanged(name: str, world: CompiledWorld, misuse: Callable[[Backend], object]) -> None:
    with make_backend(name, world) as sim:
        sim.step()
        before, joints = sim.body_states(), sim.joint_states()
        with pytest.raises(ContractViolation, match=rf"^{name}: "):
            misuse(sim)
        after = sim.body_states()
        for field in ("pos", "quat", "lin_vel", "ang_vel"):  # refused before any engine call: nothing moved
            assert np.array_equal(getattr(before, field), getattr(after, field)), field
        assert np.array_equal(joints.velocity, sim.joint_states().velocity, equal_nan=True)
        sim.step()  # and the backend goes on working


@pytest.mark.parametrize("case", list(_MISUSE))
def test_misuse_is_a_contract_violation_and_changes_nothing(any_backend: str, case: str) -> None:
    _refused_and_unchanged(any_backend, _misuse_world(any_backend), _MISUSE[case])


def test_set_motor_on_a_joint_without_a_motor_is_a_contract_violation(
    backend_name: str, backend_cls: type[Backend]
) -> None:
    require(backend_cls, Capability.JOINT_BALL)
    _refused_and_unchanged(backend_name, w.misuse(with_ball=True), lambda sim: sim.set_motor(1, 0.1, 1.0))


def test_forces_on_bodies_that_are_not_dynamic_have_no_effect(any_backend: str) -> None:
    """ODE: a static geom has no body to push; a kinematic body goes where it is told."""
    with make_backend(any_backend, _misuse_world(any_backend)) as sim:
        start = sim.body_states()
        sim.apply_force(0, (1e4, 0.0, 0.0), (0.0, 0.0, 1e4))
        sim.apply_force(1, (1e4, 0.0, 0.0), (0.0, 0.0, 1e4))
        sim.step()
        s = sim.body_states()
    exact = tol("kinematic_pose", any_backend)
    assert s.pos[:2] == pytest.approx(start.pos[:2], abs=exact)
    assert s.lin_vel[1] == pytest.approx(ZERO, abs=exact) and s.ang_vel[1] == pytest.approx(ZERO, abs=exact)


# 16. calls after close() -----------------------------------------------------------------------------

_CALLS: dict[str, Callable[[Backend], object]] = {
    "step": lambda sim: sim.step(),
    "body_states": lambda sim: sim.body_states(),
    "joint_states": lambda sim: sim.joint_states(),
    "contacts": lambda sim: sim.contacts(),
    "settings": lambda sim: sim.settings(),
    "drain_messages": lambda sim: sim.drain_messages(),
    "set_kinematic": lambda sim: sim.set_kinematic(1, *_POSE),
    "set_motor": lambda sim: sim.set_motor(0, 0.1, 1.0),
    "apply_force": lambda sim: sim.apply_force(2, (1.0, 0.0, 0.0), ZERO),
    "reset_body": lambda sim: sim.reset_body(2, *_POSE),
}


def test_every_call_after_close_is_a_contract_violation(any_backend: str) -> None:
    sim = make_backend(any_backend, _misuse_world(any_backend))
    sim.step()
    sim.close()
    sim.close()  # idempotent
    assert sim.closed
    for method, call in _CALLS.items():
        with pytest.raises(ContractViolation, match=rf"{method}\(\) called after close\(\)"):
            call(sim)


# 17. engine errors, and only those, are engine failures ------------------------------------------------

_HOOKS: dict[str, tuple[str, Callable[[Backend], object]]] = {
    "step": ("_step", lambda sim: sim.step()),
    "body_states": ("_body_states", lambda sim: sim.body_states()),
    "joint_states": ("_joint_states", lambda sim: sim.joint_states()),
    "contacts": ("_contacts", lambda sim: sim.contacts()),
    "settings": ("_settings", lambda sim: sim.settings()),
    "set_kinematic": ("_place_kinematic", lambda sim: sim.set_kinematic(1, *_POSE)),
    "set_motor": ("_set_motor", lambda sim: sim.set_motor(0, 0.1, 1.0)),
    "reset_body": ("_reset_body", lambda sim: sim.reset_body(2, *_POSE)),
    "close": ("_close", lambda sim: sim.close()),
}


@pytest.mark.parametrize("method", list(_HOOKS))
def test_engine_errors_become_engine_failures_and_adapter_bugs_stay_bugs(
    any_backend: str, method: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every contract method translates the engine's own exception types, and nothing else."""
    hook, call = _HOOKS[method]
    cls = get_backend(any_backend)
    raised: list[BaseException] = [TypeError("a bug in the adapter")]
    raised += [error_type("the engine says no") for error_type in cls.engine_errors]
    for exc in raised:
        sim = make_backend(any_backend, _misuse_world(any_backend))
        try:

            def fail(*args: object, exc: BaseException = exc) -> None:
                raise exc

            monkeypatch.setattr(sim, hook, fail)
            if isinstance(exc, cls.engine_errors):
                with pytest.raises(EngineFailure, match=rf"^{any_backend}: .*the engine says no") as info:
                    call(sim)
                assert info.value.backend == any_backend and info.value.__cause__ is exc
            else:
                with pytest.raises(TypeError, match="a bug in the adapter"):
                    call(sim)
        finally:
            monkeypatch.undo()
            if sim.closed:  # `close` under test: release the engine for real
                type(sim)._close(sim)
            else:
                sim.close()


# 18. substeps: contacts used during the step, mean forces ----------------------------------------------


def test_contacts_with_substeps_are_those_used_during_the_step(backend_name: str, backend_cls: type[Backend]) -> None:
    """Four substeps of 0.01 s. Resting, the pair's normal force is the mean over the substeps (m*g, not
    4*m*g). Kicked up, the box leaves the ground during the first substep: the pair is still reported
    for that step (it was touching when the step began), and for no later step."""
    require(backend_cls, Capability.SUBSTEPS)
    world = w.resting_box(substeps=4)
    m, h = world.bodies[1].mass, world.dt / world.substeps
    kick = 2000.0  # N: a = kick/m - g = 138.3 m/s^2, so the box is 13.8 mm up after the first substep
    with make_backend(backend_name, world) as sim:
        for _ in range(25):  # 1 s: settled
            sim.step()
        resting = sim.contacts()
        sim.apply_force(1, (0.0, 0.0, kick), ZERO)
        sim.step()
        lifted, z = sim.contacts(), float(sim.body_states().pos[1, 2])
        sim.step()
        flying = sim.contacts()
    assert [(c.a, c.b) for c in resting] == [(0, 1)] and resting[0].points >= 1
    if not math.isnan(resting[0].normal_force):
        assert resting[0].normal_force == pytest.approx(m * G, rel=tol("contact_force", backend_name))
    # The end of the kicked step is well clear of the ground: the contact came from the step's start.
    assert z - 0.15 > (kick / m - G) * h * h - tol("resting_height", backend_name)
    assert [(c.a, c.b) for c in lifted] == [(0, 1)] and lifted[0].points >= 1
    if not math.isnan(lifted[0].normal_force):  # the box accelerates away: at most a quarter of m*g on average
        assert 0.0 <= lifted[0].normal_force < 0.25 * m * G
    assert flying == []


def test_motor_force_with_substeps_is_the_mean(backend_name: str, backend_cls: type[Backend]) -> None:
    """The door (400 kg, fmax 100 N: 0.0025 m/s per 0.01 s substep) is asked for 0.004 m/s: 100 N in the
    first substep, the remaining 0.0015 m/s (60 N) in the second, 0 N in the last two: a mean of 40 N
    (the last substep alone says 0, the sum 160). Whatever the engine's row does, the motor is the only
    force along the axis, so the mean force is also exactly m*v/dt (momentum)."""
    require(backend_cls, Capability.SUBSTEPS)
    _require_joint(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR)
    world = w.lab_door_substeps(4)
    fmax, target = 100.0, 0.004
    m, h = world.bodies[0].mass, world.dt / world.substeps
    forces = [fmax, (target - fmax / m * h) * m / h, 0.0, 0.0]  # 100, 60, 0, 0
    with make_backend(backend_name, world) as sim:
        sim.set_motor(0, target, fmax)
        sim.step()
        js = sim.joint_states()
    assert js.velocity[0] == pytest.approx(target, rel=tol("motor_velocity", backend_name))
    assert js.motor_force[0] == pytest.approx(sum(forces) / 4, rel=tol("motor_force", backend_name))
    assert js.motor_force[0] == pytest.approx(m * js.velocity[0] / world.dt, rel=tol("momentum", backend_name))


# 19. a turning kinematic body carries what rests on it ---------------------------------------------


def test_turning_kinematic_body_carries_what_rests_on_it(backend_name: str, backend_cls: type[Backend]) -> None:
    """A turntable spun at omega about z, set each step as the runner does (pose and angular velocity),
    carries a cube resting 0.5 m from the axis. Friction (mu*g = 9.81 m/s^2) brings the cube to the
    table's speed omega*r within omega*r/(mu*g) = 0.051 s, during which it trails by (omega*r)^2/(2*mu*g)
    of arc; omega^2*r = 0.5 m/s^2 of centripetal pull is far below mu*g, so it then turns with the table.
    Without the angular velocity (a teleported table) it would stay where it was."""
    require(backend_cls, Capability.KINEMATIC)
    world = w.turntable(mu=1.0)
    omega, r, mu, steps, dt = 1.0, 0.5, 1.0, 100, world.dt
    lag = (omega * r) ** 2 / (2 * mu * G) / r  # rad: the slip, 0.0255
    with make_backend(backend_name, world) as sim:
        for k in range(steps):
            quat = quat_from_axis_angle((0.0, 0.0, 1.0), omega * k * dt)
            sim.set_kinematic(0, (0.0, 0.0, 0.5), quat, ZERO, (0.0, 0.0, omega))
            sim.step()
        s = sim.body_states()
    t = steps * dt
    table = quat_from_axis_angle((0.0, 0.0, 1.0), omega * t)
    exact = tol("kinematic_pose", backend_name)
    assert _same_rotation(s.quat[0], table) == pytest.approx(table, abs=exact)
    x, y = float(s.pos[1, 0]), float(s.pos[1, 1])
    assert math.atan2(y, x) == pytest.approx(omega * t - lag, abs=lag)  # between omega*t - 2*lag and omega*t
    assert math.hypot(x, y) == pytest.approx(r, abs=lag * r)  # the slip moves it at most its own arc
    speed = math.hypot(float(s.lin_vel[1, 0]), float(s.lin_vel[1, 1]))
    assert speed == pytest.approx(omega * r, rel=tol("kinematic_carry", backend_name))
    assert float(s.ang_vel[1, 2]) == pytest.approx(omega, rel=tol("kinematic_carry", backend_name))
