"""``backends._kit.stacks``: the tallest column a world starts with, and whether it is dropped or resting.

Backends size their solvers from it and refuse columns beyond their measured limits (docs/backends/*.md,
"Stacking"), so its geometry is checked here on worlds whose answer is known by construction: a column of
boxes dropped with gaps, the same column resting (overlapping 1e-5 m, as conformance 12 and 16 start),
boxes side by side, a column next to a single box, a tilted column under tilted gravity, spheres, and a
static ground that never counts. Nothing here runs an engine.
"""

from __future__ import annotations

import math

import pytest

from backends._kit.stacks import LANDING_GAP, Stacks, stack_height, stacks
from backends.types import BodySpec, CompiledWorld, Motion, Shape, ShapeKind, Surface

SIDE = 0.3


def _box(name: str, pos: tuple[float, float, float], motion: Motion = Motion.DYNAMIC,
         quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)) -> BodySpec:  # fmt: skip
    return BodySpec(name, motion, Shape(ShapeKind.BOX, size=(SIDE, SIDE, SIDE)), 13.5, (0.2, 0.2, 0.2), pos, quat)


def _world(bodies: list[BodySpec], gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)) -> CompiledWorld:
    ground = BodySpec("ground", Motion.STATIC, Shape(ShapeKind.PLANE), 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                      (1.0, 0.0, 0.0, 0.0))  # fmt: skip
    return CompiledWorld(name="stack", gravity=gravity, dt=0.01, substeps=1, duration=1.0,
                         bodies=(ground, *bodies), joints=(), default_surface=Surface(), pair_surfaces=())  # fmt: skip


def _column(n: int, gap: float, shift: float = 0.0) -> list[BodySpec]:
    """box_pile's column: box i at height SIDE/2 + gap + i (SIDE + gap), shifted i*shift along x."""
    return [_box(f"crate_{i}", (i * shift, 0.0, SIDE / 2 + gap + i * (SIDE + gap))) for i in range(n)]


@pytest.mark.parametrize("n", [2, 5, 30])
def test_a_dropped_column_is_as_tall_as_its_boxes_and_lands(n: int) -> None:
    assert stacks(_world(_column(n, gap=0.02, shift=0.0015))) == Stacks(n, n)


def test_one_box_dropped_on_the_ground_is_a_column_of_one_that_lands_on_nothing_dynamic() -> None:
    # a landing column is one in which a body falls onto another body of the column; the ground is static
    assert stacks(_world(_column(1, gap=0.02))) == Stacks(1, 0)


@pytest.mark.parametrize("n", [2, 4, 20])
def test_a_resting_column_is_tall_but_does_not_land(n: int) -> None:
    # each box 1e-5 m into the one below (conformance 12): no gap to fall through
    assert stacks(_world(_column(n, gap=-1e-5))) == Stacks(n, 0)


def test_a_gap_just_above_the_landing_threshold_lands_and_just_below_does_not() -> None:
    assert stacks(_world(_column(3, gap=2 * LANDING_GAP))).landing == 3
    assert stacks(_world(_column(3, gap=0.5 * LANDING_GAP))).landing == 0


def test_boxes_side_by_side_or_touching_edge_to_edge_do_not_stack() -> None:
    row = [_box(f"b{i}", (i * SIDE, 0.0, SIDE / 2)) for i in range(10)]  # faces touching: zero overlap
    assert stacks(_world(row)) == Stacks(1, 0)
    # a box whose footprint only touches the one below at an edge (shifted by a whole side) is not on it
    assert stack_height(_world([_box("a", (0.0, 0.0, SIDE / 2)), _box("b", (SIDE, 0.0, 1.5 * SIDE + 0.01))])) == 1


def test_the_tallest_of_several_columns_counts_and_a_lone_box_beside_it_does_not_add() -> None:
    columns = _column(6, gap=0.02) + [_box(f"c{i}", (2.0, 0.0, SIDE / 2 + i * SIDE)) for i in range(3)]
    columns.append(_box("lone", (-2.0, 0.0, 5.0)))  # high up, but over nothing
    assert stacks(_world(columns)) == Stacks(6, 6)


def test_static_bodies_are_the_ground_of_a_column_not_part_of_it() -> None:
    shelf = _box("shelf", (0.0, 0.0, SIDE / 2), motion=Motion.STATIC)
    assert (
        stack_height(_world([shelf, *[_box(f"b{i}", (0.0, 0.0, 1.5 * SIDE + i * SIDE + 0.01)) for i in range(3)]])) == 3
    )
    assert stacks(_world([shelf])) == Stacks(0, 0)


def test_up_is_against_gravity_whatever_its_direction() -> None:
    # the same dropped column laid along +x, with gravity along -x: still a column of 4
    along_x = [_box(f"b{i}", (SIDE / 2 + 0.02 + i * (SIDE + 0.02), 0.0, 0.0)) for i in range(4)]
    assert stacks(_world(along_x, gravity=(-9.81, 0.0, 0.0))) == Stacks(4, 4)
    assert stacks(_world(along_x)).tallest == 1  # under -z gravity they lie side by side


def test_turned_boxes_and_spheres_stack_by_their_extents() -> None:
    turn = (math.cos(math.pi / 8), 0.0, 0.0, math.sin(math.pi / 8))  # 45 degrees about z: footprint grows
    boxes = [_box(f"b{i}", (0.0, 0.0, SIDE / 2 + 0.02 + i * (SIDE + 0.02)), quat=turn) for i in range(3)]
    assert stacks(_world(boxes)) == Stacks(3, 3)
    ball = BodySpec("ball", Motion.DYNAMIC, Shape(ShapeKind.SPHERE, radius=0.1), 1.0, (0.004,) * 3,
                    (0.0, 0.0, 2 * SIDE + 1.0), (1.0, 0.0, 0.0, 0.0))  # fmt: skip
    assert stacks(_world([*boxes, ball])) == Stacks(4, 4)
