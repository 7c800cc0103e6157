"""``Backend.contact_points()`` (capability ``contacts:points``): every touching point of the last engine step
with its position, its normal from body a to body b and its normal force (backends/optional_contract.py)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from backends.errors import ContractViolation, UnsupportedFeature
from backends.fake import FakeBackend
from backends.testing import worlds as w
from backends.testing.tolerances import tol
from backends.types import Capability, CompiledWorld

HALF = w.LAB_BOX[0] / 2


def _resting(box_first: bool, substeps: int = 1) -> CompiledWorld:
    """The lab's box on a plane, asking for contact points; ``box_first``: the box is body 0."""
    cube = w.box("box", w.LAB_BOX, (0.0, 0.0, HALF), density=500.0)
    bodies = [cube, w.ground()] if box_first else [w.ground(), cube]
    world = w.world("box-points", bodies, substeps=substeps)
    return dataclasses.replace(world, contact_points=True)


@pytest.mark.parametrize("box_first", [False, True], ids=["ground-first", "box-first"])
def test_box_on_plane_has_four_corner_points(backend_name: str, box_first: bool) -> None:
    """After 1 s at rest: the box's 4 bottom corners, normals from a to b (+z when the ground is a, -z when
    the box is), forces summing to m g and to the pair's ``contacts()`` force."""
    world = _resting(box_first)
    with w.make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        points = sim.contact_points()
        (pair,) = sim.contacts()
    box_index = 0 if box_first else 1
    assert len(points) == 4, points
    assert {(p.a, p.b) for p in points} == {(0, 1)}
    # Corners: x, y at +-half the edge. The engines place a point on a face, between the surfaces or on the
    # corner itself, so within the resting depth of the box (tolerances "resting_height": 2 mm) of it.
    depth = tol("resting_height", backend_name)
    corners = sorted((math.copysign(HALF, p.pos[0]), math.copysign(HALF, p.pos[1])) for p in points)
    assert corners == [(-HALF, -HALF), (-HALF, HALF), (HALF, -HALF), (HALF, HALF)]
    for p in points:
        assert abs(p.pos[0]) == pytest.approx(HALF, abs=depth)
        assert abs(p.pos[1]) == pytest.approx(HALF, abs=depth)
        assert p.pos[2] == pytest.approx(0.0, abs=depth)
        assert 0.0 <= p.depth <= depth
        up = 1.0 if box_index == 1 else -1.0  # the force on b is +force * normal: the ground pushes the box up
        # unit normals: a float32 engine's 3 components each within 2^-24 of the true value
        assert p.normal == pytest.approx((0.0, 0.0, up), abs=1e-6)
        assert p.force >= 0.0
    # Sum of the forces: the weight, within the contract's resting force tolerance ("contact_force"); and the
    # pair's force of contacts() (one engine step per step: the same forces summed, perhaps in another
    # order, so within a few ulps of float64 or of ODE's float32 dot products: 1e-6 relative).
    total = sum(p.force for p in points)
    weight = world.bodies[box_index].mass * w.G
    assert total == pytest.approx(weight, rel=tol("contact_force", backend_name))
    assert total == pytest.approx(pair.normal_force, rel=1e-6)


def test_box_on_plane_substeps_last_engine_step(backend_name: str) -> None:
    """With 4 substeps the points are the last engine step's: still 4, still the weight (at rest every engine
    step carries it)."""
    world = _resting(False, substeps=4)
    with w.make_backend(backend_name, world) as sim:
        for _ in range(100):
            sim.step()
        points = sim.contact_points()
    assert len(points) == 4
    total = sum(p.force for p in points)
    assert total == pytest.approx(world.bodies[1].mass * w.G, rel=tol("contact_force_last_substep", backend_name))


def test_no_points_before_a_step_or_in_the_air(backend_name: str) -> None:
    world = dataclasses.replace(w.box_on_ground(gap=0.01, gravity=w.ZERO), contact_points=True)
    with w.make_backend(backend_name, world) as sim:
        assert sim.contact_points() == []
        sim.step()
        assert sim.contact_points() == []


def test_points_refused_up_front_without_the_capability() -> None:
    """A backend that does not declare contacts:points refuses a world that asks for them before building it,
    and its contact_points() is a contract violation, not an engine crash."""
    assert Capability.CONTACT_POINTS not in FakeBackend.capabilities
    world = _resting(False)
    with pytest.raises(UnsupportedFeature, match="contacts:points"):
        w.make_backend("fake", world)
    sim = FakeBackend(dataclasses.replace(world, contact_points=False))
    with pytest.raises(ContractViolation, match="contacts:points"):
        sim.contact_points()
    sim.close()


def test_points_are_sorted_by_pair(backend_name: str) -> None:
    """Two boxes side by side on the plane: the points come sorted by (a, b), each with a unit normal."""
    left = w.box("left", w.LAB_BOX, (-0.5, 0.0, HALF), density=500.0)
    right = w.box("right", w.LAB_BOX, (0.5, 0.0, HALF), density=500.0)
    world = dataclasses.replace(w.world("two", [left, w.ground(), right]), contact_points=True)
    with w.make_backend(backend_name, world) as sim:
        for _ in range(20):
            sim.step()
        points = sim.contact_points()
    pairs = [(p.a, p.b) for p in points]
    assert pairs == sorted(pairs) and set(pairs) == {(0, 1), (1, 2)}
    for p in points:
        assert np.linalg.norm(p.normal) == pytest.approx(1.0, abs=1e-6)
        assert p.normal[2] == pytest.approx(-1.0 if p.a == 0 else 1.0, abs=1e-6)  # a=left above b=ground
