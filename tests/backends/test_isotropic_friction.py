"""Coulomb friction is isotropic: the same deceleration whatever the direction of the slip (issue 17).

The language's ``mu`` bounds the friction force by mu times the normal force, in whatever direction the
contact slips: the friction cone. A box launched on a floor at v0 along any horizontal direction feels
-mu*m*g along its velocity, so it decelerates at mu*g along a straight line and stops after
v0^2/(2*mu*g) (2 m/s, mu 0.3: 0.6796 m). With semi-implicit Euler (v -= mu*g*dt, then x += v*dt) the
engines stop after the discrete sum ``coulomb_stop`` (0.6785 m at dt 1 ms), which is what is compared.
A friction pyramid whose edges are the world's x and y (ODE's and DART's default contact directions)
brakes each velocity component at mu*g: along the diagonal the deceleration is sqrt(2)*mu*g and the box
stops after 0.4795 m, 29 % short, and off the axes and diagonals it also turns.
The friction of a box does not depend on how the box is turned either: a box yawed about z stops
after the same distance on its line.

On a plane tilted by theta whose downhill direction points at azimuth phi, a box sliding downhill
accelerates at g*(sin(theta) - mu*cos(theta)) along the fall line (30 deg, mu 0.2: 3.206 m/s^2) with no
sideways motion; semi-implicit Euler is exact for a constant acceleration, so the speed gain after t is
a*t exactly. Tolerances: ``friction`` of tolerances.py for the deceleration and the gain (3 %, the
issue's acceptance figure); the sideways drift must stay within the same 3 % of the distance (a path
turned by at most 0.03 rad), where the axis-aligned pyramid turns a 22.5 degree launch by 0.1 rad.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from backends.geometry import quat_mul
from backends.testing import worlds as w
from backends.testing.tolerances import tol
from backends.testing.worlds import G, coulomb_stop, make_backend
from backends.types import BodyStates, Motion, Shape, ShapeKind, Surface

V0, MU, DT = 2.0, 0.3, 0.001


@pytest.mark.parametrize("degrees", [0.0, 22.5, 45.0, 67.5, 90.0, 135.0])
def test_sliding_box_stops_after_the_same_distance_in_every_direction(backend_name: str, degrees: float) -> None:
    s = _slide(backend_name, degrees, yaw=0.0)
    assert float(np.linalg.norm(s.lin_vel[1])) < 1e-3


def _slide(backend_name: str, degrees: float, yaw: float) -> BodyStates:
    """A box (yawed by ``yaw``) launched at V0 towards ``degrees`` on a floor: it must stop after the
    Coulomb distance along its launch direction, and not drift sideways; its state after 0.8 s."""
    direction = np.array([math.cos(math.radians(degrees)), math.sin(math.radians(degrees)), 0.0])
    half = math.radians(yaw) / 2
    # resting 1e-5 m deep, as conformance 8: a box exactly touching gets its first contact a step late
    box = w.box("box", (0.2, 0.2, 0.2), (0.0, 0.0, 0.09999), density=500.0, lin_vel=tuple(V0 * direction),
                quat=(math.cos(half), 0.0, 0.0, math.sin(half)))  # fmt: skip
    world = w.world("slide", [w.ground(), box], surface=Surface(bounce=0.0, mu=MU), dt=DT, steps=800)
    with make_backend(backend_name, world) as sim:
        for _ in range(800):  # stops at 0.68 s
            sim.step()
        s = sim.body_states()
    along = float(s.pos[1] @ direction)
    sideways = float(np.linalg.norm(s.pos[1, :2] - along * direction[:2]))
    expected = coulomb_stop(V0, MU, DT)
    assert along == pytest.approx(expected, rel=tol("friction", backend_name))
    assert sideways < tol("friction", backend_name) * expected
    return s


#: Bullet's implicit friction cone (btMultiBodyConstraintSolver::resolveConeFrictionConstraintRows) solves
#: the two friction rows of a contact each with its own diagonal effective mass and then scales the pair
#: onto the cone. Its friction axes are btPlaneSpace1(normal) (world x/y on a floor). Where the rows'
#: effective masses differ (a box corner whose edges are turned from those axes) the clipped impulse is
#: not opposite the slip unless the slip lies along an axis (docs/backends/pybullet.md, deviation 8).
_BULLET_CONE = "pybullet: implicit cone with per-row effective masses (deviation 8 of docs/backends/pybullet.md)"


@pytest.mark.parametrize(("yaw", "degrees"), [(30.0, 0.0), (30.0, 45.0), (45.0, 30.0)])
def test_a_box_turned_about_z_stops_after_the_same_distance(
    backend_name: str, yaw: float, degrees: float, request: pytest.FixtureRequest
) -> None:
    """Friction must not depend on the box's own orientation: a box yawed by ``yaw`` slides as above."""
    if backend_name == "pybullet" and degrees % 90.0:
        # measured: +4.53 % and 18.3 mm sideways (yaw 30, 45 deg); +4.58 % and 55.3 mm (yaw 45, 30 deg)
        request.applymarker(pytest.mark.xfail(strict=True, reason=_BULLET_CONE))  # runs; must still miss
    _slide(backend_name, degrees, yaw)


@pytest.mark.parametrize("azimuth", [0.0, 45.0, 135.0, 250.0])
def test_box_slides_down_a_tilted_plane_at_the_coulomb_rate(
    backend_name: str, azimuth: float, request: pytest.FixtureRequest
) -> None:
    if backend_name == "pybullet" and azimuth in (45.0, 135.0):
        # measured: gain +3.15 % (45 deg), +3.24 % (135 deg), sideways 0.047 and 0.068 m/s; exact at 0 deg,
        # where the fall line is one of btPlaneSpace1's axes; 250 deg passes (+0.39 %, 0.0065 m/s).
        request.applymarker(pytest.mark.xfail(strict=True, reason=_BULLET_CONE))  # runs; must still miss
    tilt, phi, mu, v0, steps = math.radians(30.0), math.radians(azimuth), 0.2, 0.5, 500
    turn_z = (math.cos(phi / 2), 0.0, 0.0, math.sin(phi / 2))
    tilt_y = (math.cos(tilt / 2), 0.0, math.sin(tilt / 2), 0.0)
    q = quat_mul(turn_z, tilt_y)  # tilt about +y (downhill +x), then turn the fall line to the azimuth
    normal = np.array([math.sin(tilt) * math.cos(phi), math.sin(tilt) * math.sin(phi), math.cos(tilt)])
    downhill = np.array([math.cos(tilt) * math.cos(phi), math.cos(tilt) * math.sin(phi), -math.sin(tilt)])
    plane = w.body("ramp", Shape(ShapeKind.PLANE), w.ZERO, motion=Motion.STATIC, quat=q)
    cube = w.box("cube", (0.2, 0.2, 0.2), tuple(0.09999 * normal), density=500.0, quat=q, lin_vel=tuple(v0 * downhill))
    world = w.world("ramp", [plane, cube], surface=Surface(bounce=0.0, mu=mu), dt=DT, steps=steps)
    with make_backend(backend_name, world) as sim:
        for _ in range(steps):
            sim.step()
        v = sim.body_states().lin_vel[1]
    gain = G * (math.sin(tilt) - mu * math.cos(tilt)) * steps * DT  # 1.603 m/s
    along = float(v @ downhill)
    sideways = float(np.linalg.norm(v - along * downhill - float(v @ normal) * normal))
    assert along - v0 == pytest.approx(gain, rel=tol("friction", backend_name))
    assert sideways < tol("friction", backend_name) * gain


@pytest.mark.parametrize("azimuth", [0.0, 45.0])
@pytest.mark.parametrize("ratio", [0.95, 1.05])
def test_box_at_rest_on_a_tilted_plane_sticks_below_mu_and_slides_above(
    backend_name: str, azimuth: float, ratio: float, request: pytest.FixtureRequest
) -> None:
    """A box released at rest on a plane tilted by 30 deg sticks when tan(30 deg) < mu and slides when above.

    ``ratio`` = tan(theta)/mu: 0.95 (mu 0.608) must stick, 1.05 (mu 0.550) must slide at g*(sin - mu*cos)
    (0.233 m/s^2: 0.117 m/s after 0.5 s). A pyramid with edges along x and y holds a diagonal load up to
    sqrt(2)*mu*N, so at azimuth 45 deg it would hold the 1.05 box too. The sticking box may only creep: its
    speed stays below 1e-3 m/s (conformance 12's bound for a body at rest; the sliding one gains 0.117 m/s).
    """
    if backend_name == "pybullet" and ratio > 1.0 and azimuth == 45.0:
        # measured: 0.2513 m/s for 0.1168 (+115 %); exact at 0 deg
        request.applymarker(pytest.mark.xfail(strict=True, reason=_BULLET_CONE))  # runs; must still miss
    if backend_name == "mujoco" and ratio > 1.0:
        # measured: 0.11765 m/s for 0.11679 (+0.74 %, mujoco's bound 0.3 %) at 0 and 45 deg alike: not
        # the direction; the start from rest on a soft contact (cause not measured further)
        request.applymarker(pytest.mark.xfail(strict=True, reason="mujoco: +0.74 % gain from rest, any azimuth"))
    if backend_name == "drake" and ratio > 1.0:
        # measured: 0.1040 m/s at 0 deg (-10.9 %) and 0.1477 at 45 deg (+26 %) for 0.1168: the compliant
        # hydroelastic box (its tessellated pressure field) starts from rest at the friction limit under SAP's
        # regularised stiction (docs/backends/drake.md, deviation 4); launched boxes slide within 3 %
        request.applymarker(pytest.mark.xfail(strict=True, reason="drake: -10.9 % / +26 % from rest"))
    tilt, phi, steps = math.radians(30.0), math.radians(azimuth), 500
    mu = math.tan(tilt) / ratio
    q = quat_mul((math.cos(phi / 2), 0.0, 0.0, math.sin(phi / 2)), (math.cos(tilt / 2), 0.0, math.sin(tilt / 2), 0.0))
    normal = np.array([math.sin(tilt) * math.cos(phi), math.sin(tilt) * math.sin(phi), math.cos(tilt)])
    downhill = np.array([math.cos(tilt) * math.cos(phi), math.cos(tilt) * math.sin(phi), -math.sin(tilt)])
    plane = w.body("ramp", Shape(ShapeKind.PLANE), w.ZERO, motion=Motion.STATIC, quat=q)
    cube = w.box("cube", (0.2, 0.2, 0.2), tuple(0.09999 * normal), density=500.0, quat=q)
    world = w.world("ramp", [plane, cube], surface=Surface(bounce=0.0, mu=mu), dt=DT, steps=steps)
    with make_backend(backend_name, world) as sim:
        for _ in range(steps):
            sim.step()
        v = sim.body_states().lin_vel[1]
    if ratio < 1.0:
        assert float(np.linalg.norm(v)) < 1e-3
    else:
        gain = G * (math.sin(tilt) - mu * math.cos(tilt)) * steps * DT
        along = float(v @ downhill)
        sideways = float(np.linalg.norm(v - along * downhill - float(v @ normal) * normal))
        assert along == pytest.approx(gain, rel=tol("friction", backend_name))
        assert sideways < tol("friction", backend_name) * gain
