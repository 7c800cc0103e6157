"""DART-specific checks: the traps of notes §2-§9 and the issue's acceptance numbers, on real dartpy.

The shared suite (test_backend_contract.py) checks the contract on every backend; this module checks
what is particular to the DART adapter: commands re-issued every step, SERVO force limits, the finite
stand-in for mu = inf, per-shape surfaces under DART's min / product rules, the collision detector
option, reversed joints in a skeleton tree, batched pose reads, and the measured landing penetration.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.errors import UnsupportedFeature
from backends.testing import worlds as w
from backends.testing.worlds import ZERO, G
from backends.types import CompiledWorld, JointKind, JointSpec, Motion, Motor, PairSurface, Shape, ShapeKind, Surface

pytest.importorskip("dartpy")

from backends.dart import DartBackend, _surfaces  # noqa: E402 - after the engine check
from backends.dart._build import make_shape  # noqa: E402

LAB_DT = 0.04


@pytest.fixture(autouse=True)
def _dart_stays_silent(capfd: pytest.CaptureFixture[str]) -> object:
    """DART reports misuse (wrong vector sizes, invalid coefficients) on stderr and carries on: none here."""
    yield
    err = capfd.readouterr().err
    assert "Error" not in err and "Warning" not in err, err


def _with_options(world: CompiledWorld, **options: object) -> CompiledWorld:
    return dataclasses.replace(world, backend_options={"dart": options})


def _factory(bounce: float = 0.2, **options: object) -> CompiledWorld:
    """The lab's physics scene: box (0.3 m, 500 kg/m^3) at z 2 over the door on a slider at z 0."""
    box = w.box("box", w.LAB_BOX, (1.0, 0.0, 2.0), density=500.0)
    door = w.box("door", w.LAB_DOOR, (1.0, 0.0, 0.0), density=1000.0)
    slider = JointSpec("slider", JointKind.SLIDER, "door", None, axis=(1.0, 0.0, 0.0), motor=Motor(0.0, 100.0))
    world = w.world("factory", [box, door], joints=(slider,), dt=LAB_DT, surface=Surface(bounce=bounce, mu=5000.0))
    return _with_options(world, **options) if options else world


def _box_z(world: CompiledWorld, seconds: float = 6.0) -> np.ndarray:
    """The box's z after every step, the 1000 N kick applied for the first step only."""
    with DartBackend(world) as sim:
        sim.apply_force(0, (0.0, 0.0, 1000.0), ZERO)
        out = []
        for _ in range(round(seconds / world.dt)):
            sim.step()
            out.append(sim.body_states().pos[0, 2])
    return np.array(out)


# --- the acceptance numbers --------------------------------------------------------------------


def test_door_accelerates_at_fmax_over_m() -> None:
    world = w.lab_door()  # 400 kg door, motor vel 0.3, fmax 100
    with DartBackend(world) as sim:
        v = []
        for _ in range(30):
            sim.step()
            v.append(sim.joint_states().velocity[0])
            assert sim.joint_states().motor_force[0] == pytest.approx(100.0, rel=1e-6)
    accel = np.diff([0.0, *v[:29]]) / LAB_DT
    assert accel == pytest.approx(np.full(29, 100.0 / 400.0), rel=0.01)  # measured: 0.25000 at every step
    assert v[-1] == pytest.approx(0.3, rel=1e-9)


@pytest.mark.parametrize(("substeps", "max_engine_dt"), [(1, None), (10, None), (1, 0.01)])
def test_one_step_kick(substeps: int, max_engine_dt: float | None) -> None:
    world = w.lab_kick(substeps)
    if max_engine_dt is not None:
        world = _with_options(world, max_engine_dt=max_engine_dt)  # 4 engine steps of 0.01 s
    with DartBackend(world) as sim:
        sim.apply_force(0, (0.0, 0.0, 1000.0), ZERO)
        sim.step()
        v1 = sim.body_states().lin_vel[0, 2]
        sim.step()
        v2 = sim.body_states().lin_vel[0, 2]
    assert v1 == pytest.approx(2.5706, abs=1e-4)  # measured 2.570563
    assert v2 == pytest.approx(2.1782, abs=1e-4)  # measured 2.178163


# --- motors ------------------------------------------------------------------------------------------


def test_motor_command_reissued_every_step() -> None:
    """DART's step() resets joint commands: a command set once would stop the door after one step."""
    with DartBackend(w.lab_door()) as sim:
        for _ in range(250):  # 10 s
            sim.step()
        js = sim.joint_states()
    assert js.velocity[0] == pytest.approx(0.3, rel=1e-9)
    # 30 steps accelerating (x = 0.0004 * (1 + ... + 30) = 0.186 m), then 220 steps at 0.3 m/s.
    assert js.position[0] == pytest.approx(0.186 + 220 * 0.3 * LAB_DT, rel=1e-6)


def test_motor_force_limit_honoured() -> None:
    """A 300 N push against a 100 N motor wins at (300 - 100) / 400 m/s^2 (a VELOCITY actuator would not)."""
    with DartBackend(w.lab_door()) as sim:
        for _ in range(10):
            sim.apply_force(0, (-300.0, 0.0, 0.0), ZERO)
            sim.step()
        js = sim.joint_states()
    assert js.velocity[0] == pytest.approx(-0.5 * 10 * LAB_DT, rel=1e-6)
    assert js.motor_force[0] == pytest.approx(100.0, rel=1e-6)


def test_motor_off_coasts() -> None:
    with DartBackend(w.lab_door()) as sim:
        for _ in range(10):
            sim.step()
        sim.set_motor(0, 0.3, 0.0)  # fmax 0: off, the door keeps its 0.1 m/s
        for _ in range(10):
            sim.step()
        js = sim.joint_states()
    assert js.velocity[0] == pytest.approx(0.1, rel=1e-9)
    assert js.motor_force[0] == 0.0


def test_reversed_joint_in_tree() -> None:
    """A joint whose `body` is the skeleton's parent: coordinate, motor and force keep the world's sign."""
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 1.0), density=1000.0)  # 8 kg, root: slides on the environment
    b = w.box("b", (0.2, 0.2, 0.2), (0.3, 0.0, 1.0), density=500.0)  # 4 kg
    rail = JointSpec("rail", JointKind.SLIDER, "a", None, axis=(1.0, 0.0, 0.0))
    pull = JointSpec("pull", JointKind.SLIDER, "a", "b", axis=(1.0, 0.0, 0.0), motor=Motor(0.3, 2.0))
    world = w.world("reversed", [a, b], joints=(rail, pull), gravity=ZERO, dt=0.01)
    rate = 2.0 * (1 / 8.0 + 1 / 4.0) * world.dt  # relative acceleration 0.75 m/s^2
    with DartBackend(world) as sim:
        assert sim._joints[1].sign == -1.0  # the case under test
        v_exp = 0.0
        for k in range(1, 51):  # 0.3 m/s reached at step 40
            sim.step()
            v_exp = min(0.3, v_exp + rate)
            js, bs = sim.joint_states(), sim.body_states()
            assert js.velocity[1] == pytest.approx(v_exp, rel=1e-6)  # motion of a relative to b
            assert js.position[1] == pytest.approx(bs.pos[0, 0] - bs.pos[1, 0] + 0.3, abs=1e-9)
            assert 8.0 * bs.lin_vel[0, 0] + 4.0 * bs.lin_vel[1, 0] == pytest.approx(0.0, abs=1e-9)
            if k < 40 or k > 41:  # full force while accelerating, none at speed
                assert js.motor_force[1] == pytest.approx(2.0 if k < 40 else 0.0, abs=1e-6), f"step {k}"
        assert js.position[0] == pytest.approx(bs.pos[0, 0], abs=1e-9)


def test_jointed_groups_start_where_placed() -> None:
    """A free root with a jointed child, and a kinematic root carrying a hinged pendulum."""
    a = w.box("a", (0.2,) * 3, (0.0, 0.0, 1.0), lin_vel=(0.5, 0.0, 0.0))
    b = w.box("b", (0.2,) * 3, (0.3, 0.0, 1.0), lin_vel=(0.5, 0.0, 0.0))
    cart = w.box("cart", (0.4, 0.2, 0.1), (2.0, 0.0, 2.0), motion=Motion.KINEMATIC, lin_vel=(0.2, 0.0, 0.0))
    bob = w.box("bob", (0.1,) * 3, (2.0, 0.0, 1.5), lin_vel=(0.2, 0.0, 0.0))
    joints = (
        JointSpec("glue", JointKind.FIXED, "b", "a"),
        JointSpec("swing", JointKind.HINGE, "bob", "cart", axis=(0.0, 1.0, 0.0), anchor=(2.0, 0.0, 2.0)),
    )
    world = w.world("groups", [a, b, cart, bob], joints=joints, gravity=ZERO, dt=0.01)
    with DartBackend(world) as sim:
        s = sim.body_states()
        assert s.pos == pytest.approx(np.array([b.pos for b in world.bodies]), abs=1e-12)
        assert s.lin_vel[:, 0] == pytest.approx([0.5, 0.5, 0.2, 0.2], abs=1e-12)
        for _ in range(100):
            sim.step()
        s = sim.body_states()
    assert s.pos[:, 0] == pytest.approx([0.5, 0.8, 2.2, 2.2], abs=1e-9)
    assert s.pos[:, 2] == pytest.approx([1.0, 1.0, 2.0, 1.5], abs=1e-6)


@pytest.mark.parametrize(
    "joints",
    [
        (("ab", "a", "b"), ("bc", "b", "c"), ("ca", "c", "a")),  # a triangle
        (("a1", "a", None), ("b1", "b", None), ("ab", "a", "b")),  # two anchors in one group
    ],
    ids=["triangle", "two-anchors"],
)
def test_closed_loops_refused(joints: tuple[tuple[str, str, str | None], ...]) -> None:
    bodies = [w.box(n, (0.1, 0.1, 0.1), (i * 0.2, 0.0, 1.0)) for i, n in enumerate("abc")]
    specs = tuple(JointSpec(n, JointKind.BALL, body, other, anchor=(0.1, 0.0, 1.0)) for n, body, other in joints)
    with pytest.raises(UnsupportedFeature, match="loop"):
        DartBackend(w.world("loop", bodies, joints=specs))


# --- surfaces ----------------------------------------------------------------------------------------


def test_mu_inf_is_finite_and_silent(capfd: pytest.CaptureFixture[str]) -> None:
    world = w.world("inf", [w.ground(), w.box("b", (0.2, 0.2, 0.2), (0.0, 0.0, 0.1))], surface=Surface(mu=math.inf))
    with DartBackend(world) as sim:
        assert set(sim.settings()["friction_per_body"].values()) == {_surfaces.MU_INF}
        for _ in range(50):  # 0.5 s pushed sideways with 0.4 m*g: Coulomb friction 1e6 holds it
            sim.apply_force(1, (0.4 * 8.0 * G, 0.0, 0.0), ZERO)
            sim.step()
        assert abs(sim.body_states().pos[1, 0]) < 1e-5  # measured 3e-7 m
        assert capfd.readouterr().err == ""
        sim._bodies[1].aspects[0].setFrictionCoeff(math.inf)  # control: what DART does with inf itself
        sim.step()
        assert "friction" in capfd.readouterr().err


def test_pair_overrides_fixed_per_shape() -> None:
    pairs = (PairSurface("ground", "a", Surface(bounce=0.5, mu=0.8)),)
    bodies = [w.ground(), w.box("a", (0.2,) * 3, (0.0, 0.0, 0.1)), w.box("b", (0.2,) * 3, (1.0, 0.0, 0.1))]
    world = w.world("pairs", bodies, surface=Surface(bounce=0.2, mu=0.3), pairs=pairs)
    with DartBackend(world) as sim:
        s = sim.settings()
    assert s["surfaces"] == "fixed per shape"
    f, r = s["friction_per_body"], s["restitution_per_body"]
    for x, y in (("ground", "a"), ("ground", "b"), ("a", "b")):
        surface = world.surface(x, y)
        assert min(f[x], f[y]) == surface.mu
        assert r[x] * r[y] == pytest.approx(surface.bounce, rel=1e-12)
        assert 0.0 <= r[x] <= 1.0


def test_conflicting_touching_pairs_named() -> None:
    """Two boxes side by side on the ground: min() cannot give the three touching pairs these mu."""
    a = w.box("a", (0.2,) * 3, (0.0, 0.0, 0.1), density=500.0)
    b = w.box("b", (0.2,) * 3, (0.199, 0.0, 0.1), density=500.0)
    pairs = (PairSurface("ground", "a", Surface(mu=0.8)), PairSurface("ground", "b", Surface(mu=0.25)))
    world = w.world("conflict", [w.ground(), a, b], surface=Surface(mu=0.5), pairs=pairs)
    with DartBackend(world) as sim:
        assert sim.settings()["surfaces"] == "per step, for the touching pairs"
        with pytest.raises(UnsupportedFeature, match="`ground`-`b`.*t = 0.000"):
            sim.step()


@settings(max_examples=60, deadline=None, derandomize=True, database=None)
@given(
    st.lists(
        st.tuples(st.sampled_from([0.1, 0.3, 1.0, 5000.0, math.inf]), st.just(0.0) | st.floats(0.05, 1.0)),
        min_size=2,
        max_size=6,
    )
)
def test_surface_solver_reproduces_solvable_pairs(per_body: list[tuple[float, float]]) -> None:
    """Targets made from per-body values always have a solution; the solver finds one exactly."""
    bodies = [w.box(f"b{i}", (0.1,) * 3, (float(i), 0.0, 0.0)) for i in range(len(per_body))]
    (mu, bounce), n = zip(*per_body, strict=True), len(per_body)
    pairs = tuple(
        PairSurface(f"b{i}", f"b{j}", Surface(bounce=bounce[i] * bounce[j], mu=min(mu[i], mu[j])))
        for i in range(n)
        for j in range(i + 1, n)
    )
    world = w.world("random", bodies, pairs=pairs)
    got = _surfaces.solve(world)
    big = _surfaces.finite_mu(world)
    for p in pairs:
        i, j = world.body_index(p.a), world.body_index(p.b)
        assert min(got.friction[i], got.friction[j]) == (p.surface.mu if math.isfinite(p.surface.mu) else big)
        assert got.restitution[i] * got.restitution[j] == pytest.approx(p.surface.bounce, rel=1e-9)
        assert 0.0 <= got.restitution[i] <= 1.0


# --- shapes, detectors, states -----------------------------------------------------------------------


@pytest.mark.parametrize(
    "shape",
    [
        Shape(ShapeKind.BOX, size=(0.2, 0.4, 0.6)),
        Shape(ShapeKind.SPHERE, radius=0.1),
        Shape(ShapeKind.CAPSULE, radius=0.05, length=0.2),
        Shape(ShapeKind.CYLINDER, radius=0.1, length=0.2),
    ],
    ids=lambda s: s.kind.value,
)
def test_dart_inertia_is_odes(shape: Shape) -> None:
    """DART's shape inertia equals ODE's dMassSet* (capsule `length` = the cylindrical part in both)."""
    spec = w.body("body", shape, (0.0, 0.0, 1.0))
    assert np.diag(make_shape(shape).computeInertia(spec.mass)) == pytest.approx(spec.inertia, rel=1e-12)
    with DartBackend(w.world("one", [spec], gravity=ZERO)) as sim:
        node = sim._bodies[0].node
        assert node.getMass() == pytest.approx(spec.mass, rel=1e-12)
        assert np.diag(node.getInertia().getMoment()) == pytest.approx(spec.inertia, rel=1e-12)


@pytest.mark.parametrize(("detector", "points"), [("ode", 4), ("fcl", 1), ("bullet", 2), ("dart", 1)])
def test_collision_detector_option(detector: str, points: int) -> None:
    """Box-on-plane contact points per detector (notes §4); ODE's is the default."""
    world = w.box_on_ground()
    with DartBackend(world if detector == "ode" else _with_options(world, collision_detector=detector)) as sim:
        assert sim.settings()["collision_detector"] == detector
        for _ in range(100):
            sim.step()
        (contact,) = sim.contacts()
    assert contact.points == points
    assert contact.normal_force == pytest.approx(13.5 * G, rel=0.01)  # measured 132.43 of 132.435 N (ode)


@pytest.mark.parametrize("options", [{"collision_detector": "gjk"}, {"max_engine_dt": 0.0}])
def test_bad_option_values(options: dict[str, object]) -> None:
    with pytest.raises(UnsupportedFeature, match="Invalid `backend_options.dart"):
        DartBackend(_with_options(w.free_fall(), **options))


def test_resting_bodies_never_sleep() -> None:
    """DART deactivates slow bodies after 0.5 s by default; ODE's auto-disable is off."""
    with DartBackend(w.box_on_ground()) as sim:
        for _ in range(150):
            sim.step()
        sim.apply_force(1, (0.0, 0.0, 500.0), ZERO)
        sim.step()
        assert sim.body_states().lin_vel[1, 2] == pytest.approx(500.0 * 0.01 / 13.5 - G * 0.01, rel=0.01)


def test_batched_reads_match_body_nodes() -> None:
    """FreeJoint [rotation vector, translation] converted with numpy equals DART's own world transforms."""
    with DartBackend(w.busy()) as sim:
        for _ in range(60):
            sim.step()
        s = sim.body_states()
        for i in range(1, len(sim.world.bodies)):
            node = sim._bodies[i].node
            transform = node.getWorldTransform()
            q = transform.quaternion().wxyz()
            assert s.pos[i] == pytest.approx(transform.translation(), abs=1e-12)
            assert s.quat[i] == pytest.approx(q if np.dot(q, s.quat[i]) >= 0 else -q, abs=1e-12)
            assert s.lin_vel[i] == pytest.approx(node.getLinearVelocity(), abs=1e-12)
            assert s.ang_vel[i] == pytest.approx(node.getAngularVelocity(), abs=1e-12)


def test_box_slides_down_a_tilted_plane() -> None:
    """A static plane rotated 20 degrees: the box slides at g(sin - mu cos) and stays on the surface."""
    slope = math.radians(20.0)
    quat = (math.cos(slope / 2), math.sin(slope / 2), 0.0, 0.0)
    normal = np.array([0.0, -math.sin(slope), math.cos(slope)])
    plane = w.body("slope", Shape(ShapeKind.PLANE), (0.0, 0.0, 0.5), motion=Motion.STATIC, quat=quat)
    box = w.box("box", (0.2,) * 3, tuple(np.array([0.0, 0.0, 0.5]) + 0.1001 * normal), quat=quat, density=500.0)
    with DartBackend(w.world("slope", [plane, box], surface=Surface(mu=0.1))) as sim:
        for _ in range(50):
            sim.step()
        s = sim.body_states()
    assert np.dot(s.pos[1] - (0.0, 0.0, 0.5), normal) == pytest.approx(0.1, abs=1e-3)  # measured 0.0995
    speed = G * (math.sin(slope) - 0.1 * math.cos(slope)) * 0.5
    assert np.linalg.norm(s.lin_vel[1]) == pytest.approx(speed, rel=0.01)  # measured 1.2166 of 1.2167


@pytest.mark.parametrize(("body", "other", "sign"), [("bob", "frame", 1.0), ("frame", "bob", -1.0)])
def test_hinge_to_static_body(body: str, other: str, sign: float) -> None:
    """A hinge to a static body is the skeleton's welded root; the angle is `body` relative to `other`."""
    frame = w.box("frame", (0.1,) * 3, (0.0, 0.0, 1.5), motion=Motion.STATIC)
    bob = w.box("bob", (0.1,) * 3, (0.5, 0.0, 1.0), density=1000.0)
    hinge = JointSpec("hinge", JointKind.HINGE, body, other, axis=(0.0, 1.0, 0.0), anchor=(0.0, 0.0, 1.0))
    with DartBackend(w.world("frame", [frame, bob], joints=(hinge,), dt=0.01)) as sim:
        for _ in range(30):
            sim.step()
        swing = math.atan2(1.0 - sim.body_states().pos[1, 2], sim.body_states().pos[1, 0])
        assert sim.joint_states().position[0] == pytest.approx(sign * swing, abs=1e-9)
        assert sim.body_states().pos[0] == pytest.approx((0.0, 0.0, 1.5), abs=1e-12)
    # The shared suite's semi-implicit pendulum (offset hinge to the environment) gives 0.88252 rad.
    assert swing == pytest.approx(0.88252, abs=1e-5)


def test_static_pairs_not_reported() -> None:
    wall = w.box("wall", (1.0, 1.0, 1.0), (0.0, 0.0, 0.4), motion=Motion.STATIC)  # sunk into the ground
    with DartBackend(w.world("static", [w.ground(), wall, w.box("b", (0.2,) * 3, (3.0, 0.0, 0.1))])) as sim:
        sim.step()
        assert [(c.a, c.b) for c in sim.contacts()] == [(0, 2)]


# --- deep landings: one step of approach, then the ODE mapping's push-out ----------------------------


def test_factory_landing_penetration() -> None:
    """Lab scene: the box lands 6.4 cm deep in one 0.04 s step; the bounce lifts it back to 0.2."""
    z = _box_z(_factory())
    v_land = math.sqrt(2.5706**2 + 2 * G * (2.1028 - 0.2))  # about 6.6 m/s at the door
    depth = 0.2 - z.min()
    assert 0.01 < depth < v_land * LAB_DT  # measured 0.0644: at most one step of approach
    assert z[-1] == pytest.approx(0.2, abs=5e-4)  # measured 0.19990 at 6 s (ODE: 0.1918, its slider sags)
    assert np.abs(z[round(2.0 / LAB_DT) :] - 0.2).max() < 5e-4  # at rest from 2 s on


def test_landing_without_bounce_recovers_as_ode() -> None:
    """Without restitution the contact's position correction lifts the box as ODE's mapping does
    (backends/dart/_contact_params.py): ERP 0.2 of the depth per step, capped at 0.1 m/s, so the 6.4 cm
    landing rises at the cap while deeper than 0.1 * h / 0.2 = 2 cm, then by 0.8 a step, to the 1e-5 m
    error allowance. (DART's own constants, ERP 0.01 capped at 1 mm/s, left it 5.9 cm deep after 6 s.)"""
    z = _box_z(_factory(bounce=0.0))
    landed = int(np.argmin(z))
    rates = np.diff(z[landed : landed + 10]) / LAB_DT  # 6.4 cm down to 3 cm: all at the cap
    # the contact rows' relative CFM (1e-5 each, DART's) yields a few 1e-5 of the requested speed
    assert rates[1:] == pytest.approx(0.1, rel=1e-4)  # measured 0.099996 m/s
    # nothing below the allowance is corrected; above it the rows' CFM sags less than another allowance
    assert 1e-5 <= 0.2 - z[-1] < 2e-5  # measured 1.08e-5 m at 6 s (ODE: 8.2 mm, its slider sags)


def test_max_engine_dt_reduces_penetration() -> None:
    z = _box_z(_factory(bounce=0.0, max_engine_dt=0.004), seconds=3.0)
    assert 0.2 - z.min() < 0.01  # one 4 ms step of approach
    assert z[-1] == pytest.approx(0.2, abs=2e-3)
