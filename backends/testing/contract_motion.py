"""The contract suite, part 1: free motion, forces, inertia, joints and kinematic bodies, against ODE's formulas.

Each test builds a small world (``backends.testing.worlds``), steps it on a real engine and compares with
ODE's analytic values; per-backend tolerances are in ``backends.testing.tolerances`` with their measurements.
A test that needs a capability the backend does not declare is skipped with that reason.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from backends.base import Backend
from backends.geometry import integrate_quat, quat_from_axis_angle, quat_rotate
from backends.registry import entry
from backends.types import (
    Capability,
    CompiledWorld,
    JointKind,
    JointSpec,
    Motor,
    Precision,
    Shape,
    ShapeKind,
)

from . import worlds as w
from .tolerances import tol
from .worlds import ZERO, G, make_backend, require

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
        sim.apply_force(0, ZERO, (float(tau[0]), float(tau[1]), float(tau[2])))
        sim.step()
        got = sim.body_states().ang_vel[0]
        assert got == pytest.approx(expected, rel=rel, abs=1e-12)
        if shape_name == "sphere":  # isotropic: omega stays constant once the torque is cleared
            sim.step()
            assert sim.body_states().ang_vel[0] == pytest.approx(expected, rel=rel, abs=1e-12)


# 4. slider motor -------------------------------------------------------------------------------------


def test_slider_motor(backend_name: str, backend_cls: type[Backend]) -> None:
    require(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR)
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
    require(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR, Capability.JOINT_LIMITS)
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
    require(backend_cls, Capability.JOINT_HINGE, Capability.JOINT_LIMITS)
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
    q = w.same_rotation(bs.quat[0], quat_from_axis_angle((0.0, 1.0, 0.0), theta))
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
    require(backend_cls, *caps)
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
    require(backend_cls, *caps)
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
    require(backend_cls, Capability.JOINT_FIXED, Capability.JOINT_BETWEEN_BODIES)
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
    require(backend_cls, Capability.CONTACTS)
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
            assert w.same_rotation(s.quat[0], expected_q) == pytest.approx(expected_q, abs=exact), f"step {k}"
            assert s.lin_vel[0] == pytest.approx(lin, abs=exact)
            assert s.ang_vel[0] == pytest.approx(ang, abs=exact)
