"""Collision solids and CollisionHandlerEvent (notes §4-5): overlap tests, in/again/out, pattern tokens."""

from __future__ import annotations

import numpy as np
import pytest

from runner.compile.solids import NodeDef, SolidDef
from runner.language.patterns import expand, unsupported_token
from runner.sim.collisions import EventHandler, Pose, SolidTraverser, sphere_hits

I3 = np.eye(3)
QUAD = SolidDef("polygon", np.zeros(3), vertices=np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float))


def at(x: float, y: float, z: float, scale: float = 1.0) -> Pose:
    return Pose(np.array([x, y, z], float), I3, scale)


@pytest.mark.parametrize("z,hit", [(0.99, True), (1.0, True), (1.01, False), (-0.99, True), (-1.01, False)])
def test_sphere_against_polygon_both_sides_when_overlapping(z: float, hit: bool) -> None:
    # a still sphere: hit iff |dist| <= r, from the front or the back (notes §5, sidedness)
    assert sphere_hits(np.array([0.0, 0.0, z]), 1.0, QUAD, at(0, 0, 0)) is hit


def test_sphere_beside_polygon_hits_only_if_its_circle_reaches_the_edge() -> None:
    # centre 0.5 above the plane, 0.8 beyond the edge x = 1: the circle on the plane has radius sqrt(1-0.25)
    assert sphere_hits(np.array([1.8, 0.0, 0.5]), 1.0, QUAD, at(0, 0, 0)) is True  # 0.8 < 0.866
    assert sphere_hits(np.array([1.9, 0.0, 0.5]), 1.0, QUAD, at(0, 0, 0)) is False  # 0.9 > 0.866


def test_scale_applies_to_both_solids_as_panda3d() -> None:
    # notes §5: from r=1 under scale 2 vs into r=1: hit at distance 2.9, miss at 3.1
    sphere = SolidDef("sphere", np.zeros(3), radius=1.0)
    assert sphere_hits(np.array([2.9, 0, 0]), 2.0, sphere, at(0, 0, 0)) is True
    assert sphere_hits(np.array([3.1, 0, 0]), 2.0, sphere, at(0, 0, 0)) is False
    # into under scale 3: hit 3.9, miss 4.1
    assert sphere_hits(np.array([3.9, 0, 0]), 1.0, sphere, at(0, 0, 0, 3.0)) is True
    assert sphere_hits(np.array([4.1, 0, 0]), 1.0, sphere, at(0, 0, 0, 3.0)) is False


def test_box_solid_uses_the_closest_point() -> None:
    box = SolidDef("box", np.zeros(3), half=np.array([1.0, 1.0, 1.0]))
    assert sphere_hits(np.array([1.5, 1.5, 0.0]), 0.75, box, at(0, 0, 0)) is True  # corner distance 0.707
    assert sphere_hits(np.array([1.6, 1.6, 0.0]), 0.8, box, at(0, 0, 0)) is False  # 0.849 > 0.8


def test_in_again_out_sequence_and_order() -> None:
    handler = EventHandler(["%fn-into-%in"], ["%fn-again-%in"], ["%fn-out-%in"])
    assert [e.name for e in handler.update([("box", "door", False)])] == ["box-into-door"]
    assert [e.name for e in handler.update([("box", "door", False), ("box", "wall", False)])] == [
        "box-again-door",
        "box-into-wall",
    ]
    assert [e.name for e in handler.update([("box", "wall", False)])] == ["box-out-door", "box-again-wall"]
    assert [e.name for e in handler.update([])] == ["box-out-wall"]
    assert handler.update([]) == []


def test_no_patterns_means_no_events() -> None:
    assert EventHandler([], [], []).update([("a", "b", False)]) == []


def test_pattern_tokens() -> None:
    assert expand("%fn-into-%in", "box", "door") == "box-into-door"
    assert expand("in-%fs%is%ig", "a", "b") == "in-ttc"  # notes §4: 'in-%fs%is%ig' -> in-ttc
    assert expand("in-%fs%is%ig", "a", "b", into_is_geometry=True) == "in-ttg"
    assert unsupported_token("%(tag)fh-%in") == "%(tag)fh"
    assert unsupported_token("%fn-into-%in") is None


def test_traverser_never_tests_a_node_against_itself_and_orders_pairs() -> None:
    sphere = SolidDef("sphere", np.zeros(3), radius=1.0)
    nodes = [NodeDef("a", 0, (sphere,)), NodeDef("b", 1, (sphere,)), NodeDef("c", 2, (sphere,))]
    trav = SolidTraverser(nodes, ["a", "b"])
    hits = trav.traverse([at(0, 0, 0), at(1.5, 0, 0), at(10, 0, 0)])
    # both colliders see each other (A-into-B and B-into-A), c is too far
    assert sorted(hits) == [("a", "b", False), ("b", "a", False)]
