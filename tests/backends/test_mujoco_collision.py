"""MuJoCo's contacts come from its geom filtering, explicit contact pairs only for pair surfaces.

The adapter used to give every pair of bodies an explicit pair (O(bodies^2) to build); the geoms now
carry the world's surface and MuJoCo's own filtering decides who touches. These tests hold the two
promises of that change: the same contacts between the same bodies, and the same physics bit for bit.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from backends.testing import worlds as w
from backends.testing.worlds import make_backend
from backends.types import BodySpec, CompiledWorld, JointKind, JointSpec, Motion, PairSurface, Shape, ShapeKind, Surface

pytest.importorskip("mujoco", reason="engine not installed: pip install 'physics-scenarios[mujoco]'")


def _scene(surface: Surface, pairs: tuple[PairSurface, ...] = ()) -> CompiledWorld:
    """Boxes landing on each other, a box sliding at 2 m/s, a sphere and a capsule rolling off them."""
    bodies = [
        w.ground(),
        w.box("low", (0.3, 0.3, 0.3), (0.0, 0.0, 0.2), density=500.0),
        w.box("high", (0.2, 0.2, 0.2), (0.05, 0.0, 0.6), density=500.0, ang_vel=(0.0, 1.0, 0.0)),
        w.box("slider", (0.2, 0.2, 0.2), (1.0, 0.0, 0.1), density=500.0, lin_vel=(2.0, 0.0, 0.0)),
        w.sphere("ball", 0.1, (0.1, 0.05, 1.0), density=500.0),
        w.body("pill", Shape(ShapeKind.CAPSULE, radius=0.05, length=0.3), (-0.1, 0.0, 1.3), density=500.0),
    ]
    return w.world("scene", bodies, surface=surface, pairs=pairs, steps=150)


def _run(world: CompiledWorld) -> tuple[np.ndarray, int]:
    with make_backend("mujoco", world) as sim:
        for _ in range(150):
            sim.step()
        d = sim._d  # type: ignore[attr-defined]
        return np.concatenate([d.qpos, d.qvel]), int(sim._m.npair)  # type: ignore[attr-defined]


@pytest.mark.parametrize("bounce", [0.0, 0.3])
def test_geom_contacts_step_bit_for_bit_as_explicit_pairs(bounce: float) -> None:
    """The world's surface on the geoms gives the contacts an explicit pair per body pair gave, to the bit.

    MuJoCo combines two geoms' equal parameters into themselves (max; solmix-weighted mean with weights
    1/2, exact; min of direct solrefs) and merges an explicit pair with its geom pair, in the same order
    (body-pair signature). With bounce, the geoms' solref (normal) differs from the pair's friction solref:
    ``_coulomb.step`` sets those friction rows' reference, without which this fails with bounce 0.3.
    """
    surface = Surface(bounce=bounce, mu=0.5)
    names = [b.name for b in _scene(surface).bodies]
    every = tuple(PairSurface(a, b, surface) for a, b in itertools.combinations(names, 2))
    filtered, npair = _run(_scene(surface))
    paired, npair_paired = _run(_scene(Surface(bounce=0.1, mu=2.0), every))  # the default is never used
    assert npair == 0
    assert npair_paired == len(every)  # the ground is static, every other body dynamic: all can touch
    assert np.array_equal(filtered, paired)


def _at(name: str, size: float, pos: tuple[float, float, float], motion: Motion = Motion.DYNAMIC) -> BodySpec:
    return w.box(name, (size, size, size), pos, density=500.0, motion=motion)


def test_who_touches_whom() -> None:
    """Everything overlapping at once: the pairs in contact are those ODE programs collide.

    Not two driven bodies (static, kinematic), not one rigid body (a fixed joint), not two joined bodies;
    but a body touches the rigid partner of the body it is joined to (``a`` and ``b`` below), which
    MuJoCo's parent filtering would have dropped.
    """
    bodies = [
        w.ground(),
        _at("wall", 0.6, (0.0, 0.0, 0.0), Motion.STATIC),
        _at("plat", 0.6, (0.05, 0.0, 0.0), Motion.KINEMATIC),
        _at("a", 0.4, (0.0, 0.05, 0.05)),
        _at("a2", 0.4, (0.05, 0.05, 0.0)),
        _at("b", 0.4, (-0.05, 0.0, 0.05)),
        _at("c", 0.4, (0.0, -0.05, 0.0)),
    ]
    joints = (
        JointSpec("weld", JointKind.FIXED, "a2", "a"),
        JointSpec("hinge", JointKind.HINGE, "b", "a2", axis=(0.0, 1.0, 0.0)),
        JointSpec("to-wall", JointKind.HINGE, "c", "wall", axis=(0.0, 1.0, 0.0)),
    )
    world = w.world("overlap", bodies, joints=joints, gravity=(0.0, 0.0, 0.0), dt=0.001)
    with make_backend("mujoco", world) as sim:
        sim.step()
        touching = {(bodies[c.a].name, bodies[c.b].name) for c in sim.contacts()}
    assert touching == {
        ("ground", "a"), ("ground", "a2"), ("ground", "b"), ("ground", "c"),
        ("wall", "a"), ("wall", "a2"), ("wall", "b"),
        ("plat", "a"), ("plat", "a2"), ("plat", "b"), ("plat", "c"),
        ("a", "b"), ("a", "c"), ("a2", "c"), ("b", "c"),
    }  # fmt: skip


def test_a_thousand_bodies_need_no_contact_pair() -> None:
    """One surface for the world: no explicit pair at all (the build is linear in the bodies)."""
    crates = [_at(f"crate_{i}", 0.2, (0.3 * (i % 40), 0.3 * (i // 40), 0.099)) for i in range(1000)]
    with make_backend("mujoco", w.world("grid", [w.ground(), *crates])) as sim:
        m = sim._m  # type: ignore[attr-defined]
        assert (m.npair, m.nexclude, m.ngeom) == (0, 0, 1001)
        sim.step()
        assert len(sim.contacts()) == 1000  # every crate on the ground, none on another
