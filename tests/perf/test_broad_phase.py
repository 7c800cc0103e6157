"""The solid traverser reports exactly the pairs that testing every collider against every node reports.

Random scenes of spheres, boxes and polygons, rotated and scaled, many of them just touching: the
traverser (which may skip far pairs, see runner/sim/collisions.py) must agree with the exhaustive
``nodes_collide`` over all pairs, in the same order. About 1 s.
"""

from __future__ import annotations

import numpy as np
import pytest

from runner.sim.collisions import NodeDef, Pose, SolidDef, SolidTraverser, nodes_collide, quat_matrix


def random_solid(rng: np.random.Generator) -> SolidDef:
    kind = rng.choice(["sphere", "box", "polygon"])
    center = rng.uniform(-0.3, 0.3, 3)
    if kind == "sphere":
        return SolidDef("sphere", center, radius=float(rng.uniform(0.05, 0.6)))
    if kind == "box":
        return SolidDef("box", center, half=rng.uniform(0.05, 0.5, 3))
    a, b = rng.uniform(0.1, 0.6, 2)
    verts = np.array([[-a, -b, 0], [a, -b, 0], [a, b, 0], [-a, b, 0]]) + center
    return SolidDef("polygon", verts.mean(axis=0), vertices=verts)


def brute(nodes: list[NodeDef], colliders: list[str], poses: list[Pose]) -> list[tuple[str, str, bool]]:
    by_name = {n.name: n for n in nodes}
    return [
        (f, into.name, False)
        for f in colliders
        for into in nodes
        if into.name != f and nodes_collide(by_name[f], poses[by_name[f].body], into, poses[into.body])
    ]


@pytest.mark.parametrize("seed", range(20))
def test_traverser_equals_exhaustive_testing(seed: int) -> None:
    rng = np.random.default_rng(seed)
    bodies = int(rng.integers(2, 25))
    spread = float(rng.uniform(0.5, 4.0))  # dense scenes overlap a lot, sparse ones hardly
    poses = []
    for _ in range(bodies):
        q = rng.normal(size=4)
        poses.append(Pose(rng.uniform(-spread, spread, 3), quat_matrix(q / np.linalg.norm(q)),
                          float(rng.uniform(0.5, 2.0))))  # fmt: skip
    nodes = []
    for k in range(int(rng.integers(2, 30))):
        solids = [random_solid(rng) for _ in range(int(rng.integers(1, 3)))]
        if k % 3 == 0:  # colliders need a sphere first (Panda3D's from-solids are spheres)
            solids[0] = SolidDef("sphere", rng.uniform(-0.3, 0.3, 3), radius=float(rng.uniform(0.05, 0.6)))
            solids = [s for s in solids if s.kind == "sphere"]
        nodes.append(NodeDef(f"n{k}", int(rng.integers(0, bodies)), tuple(solids)))
    colliders = [n.name for k, n in enumerate(nodes) if k % 3 == 0]
    expected = brute(nodes, colliders, poses)
    assert SolidTraverser(nodes, colliders).traverse(poses) == expected


def test_touching_spheres_count_at_the_exact_boundary() -> None:
    sphere = SolidDef("sphere", np.zeros(3), radius=0.5)
    nodes = [NodeDef("a", 0, (sphere,)), NodeDef("b", 1, (sphere,))]
    eye = np.eye(3)
    touching = [Pose(np.zeros(3), eye, 1.0), Pose(np.array([1.0, 0.0, 0.0]), eye, 1.0)]
    apart = [Pose(np.zeros(3), eye, 1.0), Pose(np.array([1.0 + 1e-6, 0.0, 0.0]), eye, 1.0)]
    assert SolidTraverser(nodes, ["a"]).traverse(touching) == [("a", "b", False)]
    assert SolidTraverser(nodes, ["a"]).traverse(apart) == []
