"""DART's bounce gate (backends/dart/_gate.py): not reading the bounce_vel pass's contacts in the engine steps in
which no contact can bounce changes no state, on worlds where bodies do bounce, land below bounce_vel and come
to rest."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("dartpy")

from backends.dart import DartBackend  # noqa: E402 - after the engine check
from backends.dart._gate import BounceGate, body_radius  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.types import CompiledWorld, Shape, ShapeKind, Surface  # noqa: E402
from bench import measure  # noqa: E402


def _pile(bounce: float, bounce_vel: float, duration: float) -> CompiledWorld:
    world, _ = measure.world_of(measure.pile((2, 2, 3), duration))
    return dataclasses.replace(world, default_surface=Surface(bounce=bounce, bounce_vel=bounce_vel, mu=5000.0))


def _balls(bounce: float, bounce_vel: float) -> CompiledWorld:
    """Two spheres dropped from different heights: they hit at about 2 and 1.4 m/s, bounce, settle."""
    bodies = [w.ground(), w.sphere("a", 0.1, (0.0, 0.0, 0.3)), w.sphere("b", 0.1, (1.0, 0.0, 0.2))]
    return w.world("balls", bodies, dt=0.004, surface=Surface(bounce=bounce, bounce_vel=bounce_vel, mu=1.0))


def _run(world: CompiledWorld, steps: int, gate: bool) -> tuple[list[np.ndarray], int]:
    """Every step's (N, 13) rows, and how many engine steps read the pass's contacts."""
    with DartBackend(world) as sim:
        if not gate:
            sim._gate.usable = False  # type: ignore[attr-defined]
        passes = 0
        match = sim._match_touching_pairs  # type: ignore[attr-defined]

        def counted(quiet: bool = False) -> None:
            nonlocal passes
            passes += not quiet
            match(quiet)

        sim._match_touching_pairs = counted  # type: ignore[method-assign]
        rows = []
        for _ in range(steps):
            sim.step()
            rows.append(sim.body_states().rows().copy())
    return rows, passes


@pytest.mark.parametrize(
    ("world", "steps"),
    [
        (_pile(0.2, 0.1, 1.2), 300),  # the bench's surface: nothing bounces above DART's 0.1 m/s on e v
        (_pile(0.6, 0.3, 1.2), 300),  # landings bounce, resting contacts are plastic
        (_balls(0.5, 0.8), 400),  # 2 m/s bounces, 1.4 m/s bounces, the rebounds land below bounce_vel
    ],
    ids=["bench-pile", "bouncy-pile", "balls"],
)
def test_gate_changes_no_state(world: CompiledWorld, steps: int) -> None:
    gated, passes = _run(world, steps, gate=True)
    every, all_passes = _run(world, steps, gate=False)
    assert all_passes == steps
    for k, (a, b) in enumerate(zip(gated, every, strict=True)):
        assert np.array_equal(a, b), f"step {k + 1} differs"
    assert passes < steps // 2  # most steps read nothing (the bodies come to rest)
    moved = np.abs(gated[-1][1:, 2] - np.array([b.pos[2] for b in world.bodies[1:]])).max()
    assert moved > 0.005


def test_gate_covers_free_bodies_only() -> None:
    door = w.lab_door()
    assert not BounceGate(door, [], usable=True).usable  # joints: the pass runs every step
    world = _balls(0.5, 0.8)
    assert BounceGate(world, [1, 2], usable=True).usable
    assert not BounceGate(world, [1, 2], usable=False).usable
    thresholded = dataclasses.replace(world, default_surface=Surface(bounce=0.0, bounce_vel=0.8, mu=1.0))
    assert not BounceGate(thresholded, [1, 2], True).usable


def test_body_radius() -> None:
    box = w.box("b", (0.2, 0.4, 0.4), (0.0, 0.0, 0.0))
    assert body_radius(box) == pytest.approx(0.3)
    capsule = dataclasses.replace(box, shape=Shape(ShapeKind.CAPSULE, radius=0.1, length=0.4))
    assert body_radius(capsule) == pytest.approx(0.3)
