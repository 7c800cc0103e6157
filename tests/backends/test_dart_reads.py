"""DART's state reads (backends/dart/_reads.py): two free skeletons per call through a Chain, the same arrays
as each skeleton's own getters, on a real DART world."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("dartpy")

import dartpy as dart  # noqa: E402 - after the engine check

from backends.dart._reads import state_readers  # noqa: E402
from backends.registry import create_backend  # noqa: E402
from bench import measure  # noqa: E402


def _concat(readers: list) -> np.ndarray:  # type: ignore[type-arg]
    return np.concatenate([read() for read in readers])


@pytest.mark.parametrize("counts", [(2, 2, 2), (3, 1, 1)])  # an even and an odd number of free boxes
def test_paired_reads_equal_each_skeletons_own_every_step(counts: tuple[int, int, int]) -> None:
    loaded = measure.pile(counts, 0.2)
    world, steps = measure.world_of(loaded)
    backend = create_backend("dart", world)
    try:
        skeletons = [backend._bodies[i].skeleton for i in backend._free]  # type: ignore[attr-defined]
        q_read, v_read = state_readers(skeletons)
        assert len(q_read) == (len(skeletons) + 1) // 2  # one call per pair (and one for an odd last)
        for _ in range(steps):
            backend.step()
            assert np.array_equal(_concat(q_read), np.concatenate([s.getPositions() for s in skeletons]))
            assert np.array_equal(_concat(v_read), np.concatenate([s.getVelocities() for s in skeletons]))
        moved = np.concatenate([s.getPositions() for s in skeletons])[5::6]  # the boxes fell: z changed
        assert np.abs(moved - np.array([b.pos[2] for b in world.bodies[1:]])).max() > 0.005
    finally:
        backend.close()


def test_a_skeleton_that_is_not_one_free_body_is_read_alone() -> None:
    free = dart.dynamics.Skeleton("free")
    free.createFreeJointAndBodyNodePair()
    hinged = dart.dynamics.Skeleton("hinged")
    hinged.createRevoluteJointAndBodyNodePair()
    q_read, v_read = state_readers([free, hinged])
    assert len(q_read) == len(v_read) == 2  # no chain: its coordinates are not 2 x 6
    free.setPositions(np.arange(6.0))
    hinged.setPositions(np.array([0.5]))
    assert np.array_equal(_concat(q_read), np.array([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 0.5]))
