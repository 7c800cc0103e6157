"""PyBullet-only checks: surface fitting, tree building, options, errors, substep motors, teardown.

The shared suite (test_backend_contract.py) covers ODE's semantics; these cover what is specific to
the PyBullet adapter's mapping (docs/backends/pybullet.md).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pytest

from backends.errors import EngineFailure, UnsupportedFeature
from backends.registry import create_backend, is_installed
from backends.testing import worlds as w
from backends.testing.worlds import ZERO
from backends.types import (
    CompiledWorld,
    JointKind,
    JointSpec,
    Motion,
    Motor,
    PairSurface,
    Surface,
)

if TYPE_CHECKING:
    from backends.pybullet._surfaces import SurfaceFit

pytestmark = pytest.mark.skipif(not is_installed("pybullet"), reason="engine not installed: pybullet")


def _fit(world: CompiledWorld) -> SurfaceFit:
    from backends.pybullet._surfaces import fit_surfaces  # imports pybullet: only once it is known

    return fit_surfaces(world)


def _three_on_ground(pairs: tuple[PairSurface, ...], surface: Surface) -> CompiledWorld:
    bodies = [w.ground()] + [w.box(n, (0.2, 0.2, 0.2), (float(i), 0.0, 0.1)) for i, n in enumerate("abc")]
    return w.world("three", bodies, surface=surface, pairs=pairs)


# --- surfaces -----------------------------------------------------------------------------------------


def test_default_surface_is_sqrt_per_body() -> None:
    fit = _fit(_three_on_ground((), Surface(bounce=0.2, mu=5000.0, bounce_vel=0.1)))
    assert fit.method == "sqrt"
    assert fit.restitution == pytest.approx([math.sqrt(0.2)] * 4)
    assert fit.friction == pytest.approx([math.sqrt(10.0)] * 4)  # mu >= 10 (here 5000): Bullet's clamp
    assert fit.restitution_threshold == 0.1


def test_pair_overrides_are_solved_per_body() -> None:
    """Pair values that are products of per-body values are recovered exactly (6 pairs, 4 bodies)."""
    rest = {"ground": 0.9, "a": 0.8, "b": 0.5, "c": 0.3}
    fric = {"ground": 2.0, "a": 0.5, "b": 1.5, "c": 0.1}
    names = list(rest)
    pairs = tuple(
        PairSurface(x, y, Surface(bounce=rest[x] * rest[y], mu=fric[x] * fric[y]))
        for i, x in enumerate(names)
        for y in names[i + 1 :]
    )
    world = _three_on_ground(pairs, Surface(bounce=0.0, mu=1.0))
    fit = _fit(world)
    assert fit.method == "least-squares"
    for i, x in enumerate(names):
        for j, y in enumerate(names[i + 1 :], start=i + 1):
            s = world.surface(x, y)
            assert fit.friction[i] * fit.friction[j] == pytest.approx(s.mu, rel=1e-9), (x, y)
            assert fit.restitution[i] * fit.restitution[j] == pytest.approx(s.bounce, rel=1e-9), (x, y)


def test_inconsistent_pairs_are_refused_by_name() -> None:
    # ground-a 0.1, ground-b 0.1 and a-b 10 force a*b = 100 * ground^2 and a = b = 0.1/ground: impossible.
    pairs = (
        PairSurface("ground", "a", Surface(mu=0.1)),
        PairSurface("ground", "b", Surface(mu=0.1)),
        PairSurface("a", "b", Surface(mu=9.0)),
    )
    with pytest.raises(UnsupportedFeature, match=r"bodies `\w+` and `\w+` friction"):
        create_backend("pybullet", _three_on_ground(pairs, Surface(mu=0.5)))


def test_zero_bounce_pairs_are_exact_or_refused() -> None:
    """A body whose every pair has bounce 0 gets 0; a 0 pair between bouncy bodies cannot be made."""
    ball = w.sphere("ball", 0.1, (0.0, 0.0, 1.0))
    world = w.world("z", [w.ground(), ball], surface=Surface(bounce=0.5), pairs=(
        PairSurface("ground", "ball", Surface(bounce=0.0)),))
    assert _fit(world).restitution[1] == 0.0
    pairs = (PairSurface("ground", "a", Surface(bounce=0.0, mu=1.0)),)  # a-b, a-c and ground-b are 0.5
    with pytest.raises(UnsupportedFeature, match="`ground` and `a` restitution 0"):
        _fit(_three_on_ground(pairs, Surface(bounce=0.5, mu=1.0)))


def test_smallest_bounce_vel_is_used_and_noted() -> None:
    pairs = (PairSurface("ground", "a", Surface(bounce=0.5, bounce_vel=0.05, mu=1.0)),)
    world = _three_on_ground(pairs, Surface(bounce=0.5, bounce_vel=0.2, mu=1.0))
    with create_backend("pybullet", world) as sim:
        settings = sim.settings()
    assert settings["bounce_vel"] == 0.05
    # plus 1.5 g h: Bullet's approach speed includes the substep's gravity (docs, deviation 3)
    assert settings["restitution_velocity_threshold"] == pytest.approx(0.05 + 1.5 * w.G * world.dt)
    assert "0.05, 0.2" in settings["restitution_velocity_threshold_note"]


def test_infinite_mu_is_the_friction_clamp() -> None:
    """mu = inf stops a sliding plate at the clamp's deceleration, 10 g (a flat plate cannot tip)."""
    plate = w.box("plate", (0.6, 0.6, 0.02), (0.0, 0.0, 0.01), lin_vel=(2.0, 0.0, 0.0))
    world = w.world("no-slip", [w.ground(), plate], surface=Surface(mu=math.inf))
    with create_backend("pybullet", world) as sim:
        for _ in range(10):
            sim.step()
        x = sim.body_states().pos[1, 0]
    v, expected = 2.0, 0.0
    while (v := v - 10.0 * w.G * world.dt) > 0.0:
        expected += v * world.dt
    assert x == pytest.approx(expected, rel=0.02)  # 0.0129 m at dt 0.01 (0.0204 continuous)


# --- construction ---------------------------------------------------------------------------------------


def _chain() -> CompiledWorld:
    """A floating three-body chain: a -hinge- b -slider- c, all offset and rotated, zero gravity."""
    q = (math.cos(0.3), 0.0, math.sin(0.3), 0.0)
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0))
    b = w.box("b", (0.4, 0.1, 0.1), (0.35, 0.1, 1.05), quat=q)
    c = w.sphere("c", 0.05, (0.7, 0.1, 1.3))
    joints = (
        JointSpec("ab", JointKind.HINGE, "a", "b", axis=(0.0, 1.0, 0.0), anchor=(0.15, 0.05, 1.0)),
        JointSpec("bc", JointKind.SLIDER, "c", "b", axis=(0.0, 0.0, 1.0), motor=Motor(0.2, 5.0)),
    )
    return w.world("chain", [a, b, c], joints=joints, gravity=ZERO)


def test_tree_starts_at_the_world_poses() -> None:
    world = _chain()
    with create_backend("pybullet", world) as sim:
        s, js = sim.body_states(), sim.joint_states()
        assert s.pos == pytest.approx(np.array([b.pos for b in world.bodies]), abs=1e-9)
        assert s.quat == pytest.approx(np.array([b.quat for b in world.bodies]), abs=1e-9)
        assert js.position == pytest.approx([0.0, 0.0], abs=1e-12)
        for _ in range(20):
            sim.step()
        s, js = sim.body_states(), sim.joint_states()
    # The slider's motor drives c along b's axis (world z at the start) and conserves momentum.
    assert js.velocity[1] == pytest.approx(0.2, rel=1e-6)
    # Internal forces conserve momentum up to the multibody's explicit integration: measured 1.1e-4
    # kg m/s after 20 steps, against |m v| ~ 0.1 for c alone.
    momentum = sum(b.mass * s.lin_vel[i] for i, b in enumerate(world.bodies))
    assert momentum == pytest.approx(np.zeros(3), abs=1e-3)


def test_reversed_joint_flips_coordinates() -> None:
    """A joint whose `body` is the tree's parent reports body-relative-to-other, as ODE does."""
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0), density=1000.0)
    b = w.box("b", (0.2, 0.2, 0.2), (0.3, 0.0, 1.0), density=500.0)
    joint = JointSpec("s", JointKind.SLIDER, "a", "b", axis=(1.0, 0.0, 0.0), motor=Motor(0.3, 2.0))
    world = w.world("reversed", [a, b], joints=(joint,), gravity=ZERO)  # a (index 0) is the base
    with create_backend("pybullet", world) as sim:
        for _ in range(10):
            sim.step()
        s, js = sim.body_states(), sim.joint_states()
    assert js.position[0] == pytest.approx(s.pos[0, 0] - s.pos[1, 0] + 0.3, abs=1e-9)
    assert js.velocity[0] > 0.0 and s.lin_vel[0, 0] > 0.0 > s.lin_vel[1, 0]
    assert js.motor_force[0] == pytest.approx(2.0, rel=1e-6)


@pytest.mark.parametrize(
    "joints, match",
    [
        (
            (
                JointSpec("j1", JointKind.HINGE, "a", None, axis=(0.0, 1.0, 0.0)),
                JointSpec("j2", JointKind.HINGE, "a", None, axis=(1.0, 0.0, 0.0)),
            ),
            "closed loop",
        ),
        (
            (
                JointSpec("j1", JointKind.FIXED, "a", "b"),
                JointSpec("j2", JointKind.FIXED, "b", "a"),
            ),
            "closes a loop",
        ),
        ((JointSpec("j1", JointKind.FIXED, "a", "k"),), "kinematic"),
        ((JointSpec("j1", JointKind.BALL, "a", None, lo=-1.0, hi=1.0),), "no motor or stops"),
    ],
    ids=["two-env-joints", "cycle", "to-kinematic", "ball-stops"],
)
def test_unbuildable_joints_are_refused(joints: tuple[JointSpec, ...], match: str) -> None:
    bodies = [
        w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0)),
        w.box("b", (0.2, 0.2, 0.2), (0.0, 0.0, 1.3)),
        w.box("k", (0.2, 0.2, 0.2), (0.0, 0.0, 2.0), motion=Motion.KINEMATIC),
    ]
    with pytest.raises(UnsupportedFeature, match=match):
        create_backend("pybullet", w.world("bad", bodies, joints=joints))


def test_jointed_neighbours_do_not_collide() -> None:
    """Directly joined bodies overlap without contact (ODE's usual dAreConnected filter)."""
    a = w.box("a", (0.4, 0.4, 0.4), (0.0, 0.0, 1.0))
    b = w.box("b", (0.4, 0.4, 0.4), (0.1, 0.0, 1.0))  # overlaps a by 0.3 m
    joint = JointSpec("h", JointKind.HINGE, "b", None, axis=(0.0, 0.0, 1.0), anchor=(0.1, 0.0, 1.0))
    glue = JointSpec("g", JointKind.FIXED, "a", "b")
    world = w.world("overlap", [a, b], joints=(joint, glue), gravity=ZERO)
    with create_backend("pybullet", world) as sim:
        for _ in range(10):
            sim.step()
        assert sim.contacts() == []
        assert sim.body_states().pos[:, 0] == pytest.approx([0.0, 0.1], abs=1e-9)


# --- stepping details -----------------------------------------------------------------------------------


def test_motor_force_is_the_substep_mean() -> None:
    door = w.lab_door()
    world = CompiledWorld(**{**door.__dict__, "substeps": 4})
    with create_backend("pybullet", world) as sim:
        sim.step()
        js = sim.joint_states()
    assert js.velocity[0] == pytest.approx(0.01, rel=1e-9)  # fmax/m for 0.04 s, as without substeps
    assert js.motor_force[0] == pytest.approx(100.0, rel=1e-9)


def test_options_reach_the_engine() -> None:
    base = w.free_fall()
    world = CompiledWorld(**{**base.__dict__, "backend_options": {"pybullet": {"solver_iterations": 7}}})
    with create_backend("pybullet", world) as sim:
        settings = sim.settings()
    assert settings["engine_parameters"]["numSolverIterations"] == 7
    assert settings["engine_parameters"]["numSubSteps"] == 0
    assert settings["engine_parameters"]["fixedTimeStep"] == pytest.approx(base.dt)
    assert settings["damping"] == 0.0


@pytest.mark.parametrize("options", [{"solver_iterations": 0}, {"deterministic_overlapping_pairs": "yes"}])
def test_bad_option_values_are_refused(options: dict[str, object]) -> None:
    base = w.free_fall()
    world = CompiledWorld(**{**base.__dict__, "backend_options": {"pybullet": options}})
    with pytest.raises(UnsupportedFeature, match="Invalid `backend_options.pybullet"):
        create_backend("pybullet", world)


def test_initial_velocity_of_a_link_becomes_its_joint_rate() -> None:
    door = w.box("door", w.LAB_DOOR, (1.0, 0.0, 1.0), lin_vel=(0.2, 0.0, 0.0))
    joint = JointSpec("slider", JointKind.SLIDER, "door", None, axis=(1.0, 0.0, 0.0))
    with create_backend("pybullet", w.world("moving-door", [door], joints=(joint,), dt=0.04)) as sim:
        assert sim.joint_states().velocity[0] == pytest.approx(0.2, abs=1e-12)
        sim.step()
        assert sim.body_states().pos[0, 0] == pytest.approx(1.0 + 0.2 * 0.04, abs=1e-12)


def test_one_sided_stop() -> None:
    """Only `hi` given: the hinge stops there and is free the other way."""
    hinge = w.offset_hinge(hi=0.2)
    with create_backend("pybullet", hinge) as sim:
        for _ in range(100):
            sim.step()
        assert sim.joint_states().position[0] == pytest.approx(0.2, abs=2e-3)
    up = w.world("up", list(hinge.bodies), joints=hinge.joints, gravity=(0.0, 0.0, 9.81))  # swings to -pi/2
    with create_backend("pybullet", up) as sim:
        for _ in range(30):
            sim.step()
        assert sim.joint_states().position[0] < -0.5


def test_kinematic_with_substeps() -> None:
    """Placed at every substep: exact after the step and still carrying (0.296 m without substeps)."""
    base = w.kinematic_platform()
    world = CompiledWorld(**{**base.__dict__, "substeps": 4})
    with create_backend("pybullet", world) as sim:
        for k in range(100):
            sim.set_kinematic(0, (0.3 * k * world.dt, 0.0, 0.5), w.IDENTITY, (0.3, 0.0, 0.0), ZERO)
            sim.step()
        s = sim.body_states()
    assert s.pos[0] == pytest.approx((0.3, 0.0, 0.5), abs=1e-12)
    assert s.pos[1, 0] == pytest.approx(0.3, rel=0.02)


def test_non_neighbours_in_a_tree_collide() -> None:
    """Self-collision is on for links that are not directly joined (ODE collides them too)."""
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0))
    b = w.box("b", (0.2, 0.2, 0.2), (0.25, 0.0, 1.0))
    c = w.box("c", (0.2, 0.2, 0.2), (0.1, 0.0, 1.15))  # overlaps a (and b), joined only to b
    joints = (JointSpec("ab", JointKind.FIXED, "b", "a"), JointSpec("bc", JointKind.FIXED, "c", "b"))
    with create_backend("pybullet", w.world("tree", [a, b, c], joints=joints, gravity=ZERO)) as sim:
        sim.step()
        pairs = [(k.a, k.b) for k in sim.contacts()]
    assert pairs == [(0, 2)]


def test_pybullets_own_error_is_an_engine_failure() -> None:
    """The client lost behind the adapter's back: pybullet raises pybullet.error, which leaves as EngineFailure."""
    import pybullet as p

    with create_backend("pybullet", w.free_fall()) as sim:
        p.disconnect(physicsClientId=sim._c)  # type: ignore[attr-defined]
        with pytest.raises(EngineFailure, match=r"^pybullet: step 1 failed: error: Not connected") as info:
            sim.step()
        assert isinstance(info.value.__cause__, p.error)
