"""The contract suite, part 3: the edge cases every backend settles identically (the fake one included:
misuse, calls after close, engine errors; sections 15-17), substeps and a turning kinematic body (18-19)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from backends.base import Backend
from backends.errors import ContractViolation, EngineFailure
from backends.geometry import quat_from_axis_angle
from backends.registry import get_backend
from backends.types import (
    Capability,
    CompiledWorld,
)

from . import worlds as w
from .tolerances import tol
from .worlds import ZERO, G, make_backend, require

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
    "set_motors with a joint index past the end": lambda sim: sim.set_motors((0, len(sim.world.joints)), [0.1] * 2,
                                                                              [1.0] * 2),  # fmt: skip
    "set_motors with a NaN vel": lambda sim: sim.set_motors((0,), [math.nan], [1.0]),
    "set_motors with a negative fmax": lambda sim: sim.set_motors((0,), [0.1], [-1.0]),
    "set_motors with fewer values than joints": lambda sim: sim.set_motors((0,), [], []),
    "set_motors with a joint twice": lambda sim: sim.set_motors((0, 0), [0.1, 0.2], [1.0, 1.0]),
    # no model file's actuator in the world: refused by an engine without actuator:native, and by MuJoCo
    "set_control without an actuator": lambda sim: sim.set_control(0, 1.0),
    "set_control with a NaN ctrl": lambda sim: sim.set_control(0, math.nan),
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
    _refused_and_unchanged(backend_name, w.misuse(with_ball=True), lambda sim: sim.set_motors((0, 1), [0.1] * 2,
                                                                                              [1.0] * 2))  # fmt: skip


def test_set_motors_is_set_motor_for_each_joint(backend_name: str, backend_cls: type[Backend]) -> None:
    """``set_motors`` (one engine call where the engine has one) gives the engine the same commands as one
    ``set_motor`` per joint: the same states, to the bit, after commands that change every step (in the
    tuple's order, not the world's, and one joint switched off)."""
    require(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR)
    world = w.two_doors()
    commands = [((1, 0), [0.01 * k, -0.02 * k], [100.0, 50.0 if k < 5 else 0.0]) for k in range(10)]
    states = []
    for batched in (False, True):
        with make_backend(backend_name, world) as sim:
            for joints, vels, fmaxes in commands:
                if batched:
                    sim.set_motors(joints, vels, fmaxes)
                else:
                    for joint, vel, fmax in zip(joints, vels, fmaxes, strict=True):
                        sim.set_motor(joint, vel, fmax)
                sim.step()
            s, js = sim.body_states(), sim.joint_states()
            states.append((s.pos, s.lin_vel, js.position, js.velocity, js.motor_force))
    moved = states[0][3]
    assert abs(moved[1]) > 0.0 and abs(moved[0]) > 0.0  # both motors drove their doors
    for one, many in zip(*states, strict=True):
        assert np.array_equal(one, many)


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
    "set_motors": lambda sim: sim.set_motors((0,), [0.1], [1.0]),
    "apply_force": lambda sim: sim.apply_force(2, (1.0, 0.0, 0.0), ZERO),
    "reset_body": lambda sim: sim.reset_body(2, *_POSE),
    "set_control": lambda sim: sim.set_control(0, 1.0),
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
    "set_motors": ("_set_motors", lambda sim: sim.set_motors((0,), [0.1], [1.0])),
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
    require(backend_cls, Capability.CONTACTS)
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
    require(backend_cls, Capability.JOINT_SLIDER, Capability.JOINT_MOTOR)
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
    require(backend_cls, Capability.CONTACTS)
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
    assert w.same_rotation(s.quat[0], table) == pytest.approx(table, abs=exact)
    x, y = float(s.pos[1, 0]), float(s.pos[1, 1])
    assert math.atan2(y, x) == pytest.approx(omega * t - lag, abs=lag)  # between omega*t - 2*lag and omega*t
    assert math.hypot(x, y) == pytest.approx(r, abs=lag * r)  # the slip moves it at most its own arc
    speed = math.hypot(float(s.lin_vel[1, 0]), float(s.lin_vel[1, 1]))
    assert speed == pytest.approx(omega * r, rel=tol("kinematic_carry", backend_name))
    assert float(s.ang_vel[1, 2]) == pytest.approx(omega, rel=tol("kinematic_carry", backend_name))
