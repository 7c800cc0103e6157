"""ODE (panda3d) has no capsule-cylinder collider: which scenes holding both shapes run, which are refused.

Only a pair the scene would test can be missed: two bodies, one of them dynamic, not excluded
(backends/ode/_colliders.py). The expectations are free fall and resting heights, with ODE's tolerances.
"""

from __future__ import annotations

import dataclasses

import pytest

pytest.importorskip("panda3d.ode")

from backends.errors import UnsupportedFeature  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.testing.worlds import G, make_backend  # noqa: E402
from backends.types import BodySpec, Motion, PlacedShape, Shape, ShapeKind  # noqa: E402

CAPSULE = Shape(ShapeKind.CAPSULE, radius=0.05, length=0.2)
CYLINDER = Shape(ShapeKind.CYLINDER, radius=0.1, length=0.2)
#: Resting height allowance (m). At rest ODE's contact spring k = ERP/(h CFM) holds m g at a depth
#: m g h CFM / ERP = 1 kg * 9.81 m/s^2 * 0.01 s * 1e-5 / 0.2 = 4.9e-6 m (one contact; less on several). The
#: landing's penetration (at most v h = 0.44 m/s * 0.01 s = 4.4 mm after a 1 cm drop) is pushed out at ERP 0.2
#: per step: 0.8^n of it is left after n steps, below 1e-8 m after the 90 steps at rest. 1e-4 m bounds both.
REST = 1e-4


def _fall(world_bodies: list[BodySpec], steps: int = 50, **kw: object) -> tuple[float, ...]:
    world = w.world("capcyl", world_bodies, steps=steps)
    world = dataclasses.replace(world, **kw)  # type: ignore[arg-type]
    with make_backend("ode", world) as sim:
        for _ in range(steps):
            sim.step()
        return tuple(float(z) for z in sim.body_states().pos[:, 2])


def test_capsule_and_cylinder_on_one_body_run() -> None:
    """dm_control's pendulum: a decoration cylinder and the pole's capsule on one link (never tested by
    ODE). A compound of both, cylinder down, rests on the ground at the cylinder's half-length."""
    shapes = (PlacedShape(CYLINDER), PlacedShape(CAPSULE, pos=(0.0, 0.0, 0.25)))
    body = BodySpec("pole", Motion.DYNAMIC, Shape(ShapeKind.COMPOUND), 1.0, (0.01, 0.01, 0.01),
                    (0.0, 0.0, 0.11), (1.0, 0.0, 0.0, 0.0), shapes=shapes)
    _, z = _fall([w.ground(), body], steps=100)
    assert z == pytest.approx(0.1, abs=REST)


def test_an_excluded_pair_runs_and_passes_through() -> None:
    """A capsule falling onto a static cylinder, the pair excluded (a joint's links, MJCF contype): it runs,
    and the capsule falls freely through the cylinder, as the exclusion says."""
    cap = w.body("cap", CAPSULE, (0.0, 0.0, 0.5))
    cyl = w.body("cyl", CYLINDER, (0.0, 0.0, 0.0), motion=Motion.STATIC)
    z, _ = _fall([cap, cyl], excluded_pairs=(("cyl", "cap"),))
    # ODE's semi-implicit Euler: v_n = -g h n, z_n = z0 - g h^2 n (n + 1) / 2; float32 state: 1e-5 m
    assert z == pytest.approx(0.5 - G * 0.01**2 * 50 * 51 / 2, abs=1e-5)
    assert z < -0.5  # below the cylinder (top at 0.1 m): it passed through


def test_static_and_kinematic_capsule_and_cylinder_run() -> None:
    """ODE never tests static or kinematic geoms against each other (category bits): nothing to miss."""
    cap = w.body("cap", CAPSULE, (0.0, 0.0, 0.1), motion=Motion.KINEMATIC)
    cyl = w.body("cyl", CYLINDER, (0.0, 0.0, 0.0), motion=Motion.STATIC)
    ball = w.sphere("ball", 0.1, (1.0, 0.0, 0.5))
    z = _fall([cap, cyl, ball], steps=10)
    assert z[0] == pytest.approx(0.1, abs=1e-6)


def test_a_free_capsule_over_a_cylinder_is_refused() -> None:
    """A free capsule that can fall on a cylinder would pass through it: refused, both bodies named."""
    cap = w.body("cap", CAPSULE, (0.0, 0.0, 1.0))
    cyl = w.body("cyl", CYLINDER, (0.0, 0.0, 0.5), motion=Motion.STATIC)
    with pytest.raises(UnsupportedFeature, match=r"`cap` \(a capsule\) and body `cyl` \(a cylinder\).*ODE"):
        make_backend("ode", w.world("capcyl", [cap, cyl]))
