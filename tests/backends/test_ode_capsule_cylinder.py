"""Capsule against cylinder on ODE (panda3d has no collider for the pair): the prism stand-in.

A cylinder that a capsule on another body can touch (one of them dynamic, the pair not excluded) gets a
prism of ``FACETS`` facets inscribed in it, collided with capsules only (backends/ode/_colliders.py). The
expectations are analytic resting heights and free fall, with the prism's facet bound and ODE's contact
softness derived below.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("panda3d.ode")

from backends.geometry import quat_from_axis_angle  # noqa: E402
from backends.ode._colliders import FACETS, prism, prism_bodies  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.testing.worlds import G, make_backend  # noqa: E402
from backends.types import BodySpec, CompiledWorld, Motion, PlacedShape, Shape, ShapeKind  # noqa: E402
from runner.compile.program import build_program  # noqa: E402
from runner.language.load import load_scenario  # noqa: E402

CAP_R, CYL_R = 0.05, 0.1
CAPSULE = Shape(ShapeKind.CAPSULE, radius=CAP_R, length=0.2)
CYLINDER = Shape(ShapeKind.CYLINDER, radius=CYL_R, length=0.2)
#: Resting allowance (m) for ODE's contact softness. At rest its contact spring k = ERP/(h CFM) holds the
#: load at a depth m g h CFM / ERP: 2.1 kg (the capsule) * 9.81 m/s^2 * 0.01 s * 1e-5 / 0.2 = 1.0e-5 m on
#: one contact (less on several). The landing's penetration (at most v h = 0.44 m/s * 0.01 s = 4.4 mm after a
#: 1 cm drop) is pushed out at ERP 0.2 per step: 0.8^n of it is left after n steps, below 1e-8 m after the
#: 90 steps at rest. 1e-4 m bounds both.
SOFT = 1e-4
#: The prism's facets lie inside the cylinder by up to its sagitta: 1.2e-4 m for the 0.1 m radius.
SAGITTA = CYL_R * (1.0 - math.cos(math.pi / FACETS))
ALONG_X = quat_from_axis_angle((0.0, 1.0, 0.0), math.pi / 2)  # local z (a capsule's, a cylinder's axis) to x
ALONG_Y = quat_from_axis_angle((1.0, 0.0, 0.0), math.pi / 2)  # local z to -y


def _run(world: CompiledWorld, steps: int) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]]]:
    with make_backend("ode", world) as sim:
        for _ in range(steps):
            sim.step()
        s = sim.body_states()
        pairs = [(c.a, c.b) for c in sim.contacts()]
        return np.array(s.pos), np.array(s.lin_vel), pairs


def _across(steps: int = 100) -> CompiledWorld:
    """A capsule (along y) 1 cm above lying across a static cylinder (along x) centred at the origin."""
    cyl = w.body("cyl", CYLINDER, (0.0, 0.0, 0.0), motion=Motion.STATIC, quat=ALONG_X)
    cap = w.body("cap", CAPSULE, (0.0, 0.0, CYL_R + CAP_R + 0.01), quat=ALONG_Y)
    return w.world("capsule-across-cylinder", [cyl, cap], steps=steps)


@pytest.mark.parametrize(
    "options", [{}, {"collide": "auto", "impact_cfm": False, "friction_pyramid": "axes"}], ids=["callback", "auto"]
)
def test_capsule_rests_across_a_cylinder_at_the_sum_of_radii(options: dict[str, object]) -> None:
    """On the true cylinder the capsule's axis rests at r_cyl + r_cap above the cylinder's axis; on the
    prism it rests between that and SAGITTA lower, each within ODE's softness. Both contact paths (the
    Python near-callback, panda3d's autoCollide) collide the prism."""
    world = dataclasses.replace(_across(), backend_options={"ode": options})
    with make_backend("ode", world) as sim:
        assert sim._collider.mode == ("auto" if options else "callback")  # type: ignore[attr-defined]
    pos, vel, pairs = _run(world, 100)
    z = float(pos[1, 2])
    assert CYL_R + CAP_R - SAGITTA - SOFT <= z <= CYL_R + CAP_R + SOFT
    assert abs(pos[1, 0]) < 0.01 and abs(pos[1, 1]) < 0.01  # still across the top
    assert np.linalg.norm(vel[1]) < 0.01
    assert pairs == [(0, 1)]


def test_capsule_rests_on_a_falling_cylinders_end_face() -> None:
    """A dynamic cylinder upright on the ground, a capsule lying on its top face: the prism's end faces are
    the cylinder's, so the capsule rests at the cylinder's length + r_cap (two contact layers' softness)."""
    cyl = w.body("cyl", CYLINDER, (0.0, 0.0, 0.1 + 0.005))
    cap = w.body("cap", CAPSULE, (0.0, 0.0, 0.2 + CAP_R + 0.02), quat=ALONG_X)
    pos, vel, pairs = _run(w.world("capsule-on-cylinder", [w.ground(), cyl, cap], steps=100), 100)
    assert float(pos[1, 2]) == pytest.approx(0.1, abs=SOFT)
    assert float(pos[2, 2]) == pytest.approx(0.2 + CAP_R, abs=2 * SOFT)
    assert np.linalg.norm(vel[2]) < 0.01
    assert sorted(pairs) == [(0, 1), (1, 2)]


def test_same_scenario_same_states() -> None:
    """The prism's contacts are deterministic: two runs give the same bytes."""
    a, b = _run(_across(), 60), _run(_across(), 60)
    assert a[0].tobytes() == b[0].tobytes() and a[1].tobytes() == b[1].tobytes()


def test_prism_is_inscribed_and_closed() -> None:
    mesh = prism(CYL_R, 0.2)
    r = np.hypot(*np.array(mesh.vertices)[:, :2].T)
    assert r == pytest.approx(CYL_R, abs=1e-15)
    edges: dict[tuple[int, int], int] = {}
    for a, b, c in mesh.faces:
        for e in ((a, b), (b, c), (c, a)):
            edges[e] = edges.get(e, 0) + 1
    assert all(edges.get((b, a)) == 1 for a, b in edges)  # every edge once each way: closed, consistently wound
    # outward: the signed volume of a counter-clockwise (outside) winding is the prism's, pi r^2 l sin(2pi/n)/(2pi/n)
    v = np.array(mesh.vertices)
    vol = sum(np.dot(v[a], np.cross(v[b], v[c])) for a, b, c in mesh.faces) / 6.0
    n = FACETS
    assert vol == pytest.approx(n / 2 * CYL_R**2 * math.sin(2 * math.pi / n) * 0.2, rel=1e-12)


def test_capsule_and_cylinder_on_one_body_need_no_prism() -> None:
    """dm_control's pendulum: a decoration cylinder and the pole's capsule on one link (ODE never tests two
    geoms of one body). A compound of both, cylinder down, rests on the ground at the cylinder's half-length."""
    shapes = (PlacedShape(CYLINDER), PlacedShape(CAPSULE, pos=(0.0, 0.0, 0.25)))
    body = BodySpec("pole", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), 1.0, (0.01, 0.01, 0.01),
                    (0.0, 0.0, 0.11), (1.0, 0.0, 0.0, 0.0), shapes=shapes)
    world = w.world("one-body", [w.ground(), body], steps=100)
    assert prism_bodies(world) == frozenset()
    pos, _, _ = _run(world, 100)
    assert float(pos[1, 2]) == pytest.approx(0.1, abs=SOFT)


def test_an_excluded_pair_passes_through() -> None:
    """A capsule falling onto a static cylinder, the pair excluded (a joint's links, MJCF contype): no prism,
    and the capsule falls freely through the cylinder, as the exclusion says."""
    cap = w.body("cap", CAPSULE, (0.0, 0.0, 0.5))
    cyl = w.body("cyl", CYLINDER, (0.0, 0.0, 0.0), motion=Motion.STATIC)
    world = dataclasses.replace(w.world("excluded", [cap, cyl], steps=50), excluded_pairs=(("cyl", "cap"),))
    assert prism_bodies(world) == frozenset()
    pos, _, pairs = _run(world, 50)
    # ODE's semi-implicit Euler: v_n = -g h n, z_n = z0 - g h^2 n (n + 1) / 2; float32 state: 1e-5 m
    assert float(pos[0, 2]) == pytest.approx(0.5 - G * 0.01**2 * 50 * 51 / 2, abs=1e-5)
    assert pairs == []


def test_only_cylinders_a_capsule_can_touch_get_a_prism() -> None:
    """Static and kinematic shapes never meet (category bits); a free capsule meets both cylinders."""
    still = w.body("still", CAPSULE, (0.0, 0.0, 0.1), motion=Motion.KINEMATIC)
    ground_cyl = w.body("ground_cyl", CYLINDER, (0.0, 0.0, 0.0), motion=Motion.STATIC)
    assert prism_bodies(w.world("still", [still, ground_cyl])) == frozenset()
    free = w.body("free", CAPSULE, (1.0, 0.0, 1.0))
    moving_cyl = w.body("moving_cyl", CYLINDER, (2.0, 0.0, 1.0))
    assert prism_bodies(w.world("free", [still, ground_cyl, free, moving_cyl])) == frozenset({1, 3})


def test_prisms_follow_compound_shapes_and_com_offsets() -> None:
    """Robot bodies (compound shapes, a COM off the frame): the prism takes its cylinder's pose, static
    (placed in the world) or moving (a geom offset from the COM). A static compound holds a cylinder turned to
    lie along x at (0, 0, 0.3); a dynamic compound (a 0.2 m box, an upright cylinder on it, its COM 5 cm up)
    stands on the ground. Capsules dropped 1 cm rest across the first at 0.3 + r_cyl + r_cap (within the
    sagitta) and on the second's top face at 0.2 + 0.2 + r_cap."""
    lying = PlacedShape(CYLINDER, pos=(0.0, 0.0, 0.3), quat=ALONG_X)
    rack = BodySpec("rack", Motion.STATIC, Shape(ShapeKind.COMPOUND), 0.0, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0),
                    (1.0, 0.0, 0.0, 0.0), shapes=(lying,))
    on_rack = w.body("on_rack", CAPSULE, (1.0, 0.0, 0.3 + CYL_R + CAP_R + 0.01), quat=ALONG_Y)
    base = PlacedShape(Shape(ShapeKind.BOX, size=(0.2, 0.2, 0.2)))
    post = PlacedShape(CYLINDER, pos=(0.0, 0.0, 0.2))
    stand = BodySpec("stand", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), 2.0, (0.02, 0.02, 0.02),
                     (-1.0, 0.0, 0.1 + 0.005), (1.0, 0.0, 0.0, 0.0), shapes=(base, post), com=(0.0, 0.0, 0.05))
    on_stand = w.body("on_stand", CAPSULE, (-1.0, 0.0, 0.3 + 0.1 + CAP_R + 0.02), quat=ALONG_X)
    world = w.world("compound", [w.ground(), rack, on_rack, stand, on_stand], steps=100)
    assert prism_bodies(world) == frozenset({1, 3})
    pos, vel, pairs = _run(world, 100)
    assert 0.3 + CYL_R + CAP_R - SAGITTA - SOFT <= float(pos[2, 2]) <= 0.3 + CYL_R + CAP_R + SOFT
    assert float(pos[3, 2]) == pytest.approx(0.1, abs=SOFT)
    assert float(pos[4, 2]) == pytest.approx(0.4 + CAP_R, abs=2 * SOFT)
    assert np.linalg.norm(vel[[2, 4]], axis=1).max() < 0.01
    assert sorted(pairs) == [(0, 3), (1, 2), (3, 4)]


_MJCF = """<mujoco model="capsule-on-roller">
  <worldbody>
    <geom name="floor" type="plane" size="2 2 .1"/>
    <geom name="roller" type="cylinder" fromto="0 -.3 .2 0 .3 .2" size=".1"/>
    <body name="bar" pos="0 0 .36">
      <freejoint/>
      <geom name="bar" type="capsule" fromto="-.2 0 0 .2 0 0" size=".05" density="1000"/>
    </body>
    <body name="arm" pos="1 0 .5">
      <joint name="swing" type="hinge" axis="0 1 0"/>
      <geom name="hub" type="cylinder" fromto="0 -.03 0 0 .03 0" size=".04"/>
      <geom name="upper" type="capsule" fromto="0 0 0 0 0 -.2" size=".02"/>
      <body name="forearm" pos="0 0 -.2">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom name="lower" type="capsule" fromto="0 0 0 .2 0 0" size=".02"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

_SCENARIO = """schema_version: 1
scenario: capsule-on-roller
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 1.0}
robots:
  model: {mjcf: model.xml}
"""


def test_an_mjcf_capsule_rests_on_its_cylinder(tmp_path: Path) -> None:
    """An MJCF file as MuJoCo reads it: a free capsule bar (r 0.05) dropped 1 cm across the world body's
    roller (r 0.1, axis along y at z 0.2) rests at 0.2 + 0.1 + 0.05 within the sagitta. The arm's hub
    cylinder shares its link with a capsule and is its forearm's parent (MuJoCo's parent filter excludes the
    pair): it needs a prism for the free bar only."""
    (tmp_path / "model.xml").write_text(_MJCF)
    (tmp_path / "scene.yaml").write_text(_SCENARIO)
    world = build_program(load_scenario(tmp_path / "scene.yaml")).world
    assert sorted(world.bodies[i].name for i in prism_bodies(world)) == ["model.arm", "model.worldbody"]
    assert ("model.arm", "model.forearm") in world.excluded_pairs
    no_bar = dataclasses.replace(world, bodies=tuple(b for b in world.bodies if b.name != "model.bar"))
    # the roller still needs one for the arm's capsules (MuJoCo's parent filter never applies to the world body)
    assert [no_bar.bodies[i].name for i in prism_bodies(no_bar)] == ["model.worldbody"]
    bar = world.body_index("model.bar")
    pos, vel, _ = _run(world, 100)
    assert 0.35 - SAGITTA - SOFT <= float(pos[bar, 2]) <= 0.35 + SOFT
    assert np.linalg.norm(vel[bar]) < 0.01


def test_imported_model_counts_no_prism() -> None:
    """``imported_model()`` reports the world's shapes: a dynamic cylinder with its prism is one shape."""
    cyl = w.body("cyl", CYLINDER, (0.0, 0.0, 0.1 + 0.005))
    cap = w.body("cap", CAPSULE, (0.0, 0.0, 0.2 + CAP_R + 0.02), quat=ALONG_X)
    world = w.world("imported", [w.ground(), cyl, cap])
    assert prism_bodies(world) == frozenset({1})
    with make_backend("ode", world) as sim:
        imported = sim.imported_model()
    assert imported is not None
    assert {b.name: b.shapes for b in imported.bodies} == {"cyl": 1, "cap": 1}
