"""Panda3D's HPR convention (notes §6) and ODE's mass formulas (ode-on-backends §1)."""

from __future__ import annotations

import math

import pytest

from backends.geometry import integrate_quat, quat_rotate, rotation_vector
from backends.types import Shape, ShapeKind
from runner.compile.world import mass_properties, volume
from runner.language.hpr import hpr_to_quat, quat_to_hpr


def close(a, b, tol=1e-12):  # noqa: ANN001, ANN201
    return all(abs(x - y) <= tol for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize(
    "hpr,vector,expected",
    [
        ((90, 0, 0), (0, 1, 0), (-1, 0, 0)),  # heading +90: forward turns left
        ((0, 90, 0), (0, 1, 0), (0, 0, 1)),  # pitch +90: nose up
        ((0, 0, 90), (1, 0, 0), (0, 0, -1)),  # roll +90: right side down
    ],
)
def test_hpr_axes_as_panda3d(hpr, vector, expected) -> None:  # noqa: ANN001
    assert close(quat_rotate(hpr_to_quat(hpr), vector), expected)


def test_hpr_composition_order_roll_then_pitch_then_heading() -> None:
    # column form T*Rh*Rp*Rr: a vector is rolled first, then pitched, then turned
    h, p, r = hpr_to_quat((90, 0, 0)), hpr_to_quat((0, 90, 0)), hpr_to_quat((0, 0, 90))
    v = (1.0, 0.0, 0.0)
    stepwise = quat_rotate(h, quat_rotate(p, quat_rotate(r, v)))
    assert close(quat_rotate(hpr_to_quat((90, 90, 90)), v), stepwise)


@pytest.mark.parametrize("hpr", [(30, 20, 10), (-120, -45, 170), (45, 0, 0), (0, 89, 0)])
def test_quat_to_hpr_inverts(hpr) -> None:  # noqa: ANN001
    assert close(quat_to_hpr(hpr_to_quat(hpr)), hpr, 1e-9)


def test_rotation_vector_and_integration_round_trip() -> None:
    q0, q1 = hpr_to_quat((10, 5, 0)), hpr_to_quat((25, 5, 3))
    rv = rotation_vector(q0, q1)
    assert close(integrate_quat(q0, rv, 1.0), q1, 1e-12)


def test_box_mass_and_inertia_as_ode() -> None:
    shape = Shape(ShapeKind.BOX, size=(0.3, 0.3, 0.3))
    mass = 500 * volume(shape)
    assert mass == pytest.approx(13.5)
    assert mass_properties(shape, mass) == pytest.approx((0.2025, 0.2025, 0.2025))
    door = Shape(ShapeKind.BOX, size=(2, 2, 0.1))
    assert 1000 * volume(door) == pytest.approx(400)


def test_sphere_capsule_cylinder_as_ode() -> None:
    sphere = Shape(ShapeKind.SPHERE, radius=0.1)
    m = 1000 * volume(sphere)
    assert m == pytest.approx(4.18879, rel=1e-5)
    assert mass_properties(sphere, m)[0] == pytest.approx(0.016755, rel=1e-4)
    cyl = Shape(ShapeKind.CYLINDER, radius=0.1, length=0.4)
    m = volume(cyl) * 1000
    assert m == pytest.approx(math.pi * 0.01 * 0.4 * 1000)
    ix, iy, iz = mass_properties(cyl, m)
    assert iz == pytest.approx(0.5 * m * 0.01) and ix == pytest.approx(m * (0.25 * 0.01 + 0.16 / 12))
    cap = Shape(ShapeKind.CAPSULE, radius=0.1, length=0.4)
    m1, m2 = math.pi * 0.01 * 0.4 * 1000, 4 / 3 * math.pi * 0.001 * 1000  # dMassSetCapsule's two parts
    ix, _, iz = mass_properties(cap, 1000 * volume(cap))
    assert iz == pytest.approx((0.5 * m1 + 0.4 * m2) * 0.01)
    assert ix == pytest.approx(m1 * (0.25 * 0.01 + 0.16 / 12) + m2 * (0.4 * 0.01 + 0.375 * 0.1 * 0.4 + 0.25 * 0.16))
