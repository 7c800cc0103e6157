"""MujocoWarpBatch (backends/mujoco_warp/_batch.py): which worlds make one batch, and a world in a batch is the
same world run alone on mujoco_warp (docs/batch.md).

Equivalence is asserted EXACTLY (bit for bit): on Warp's CPU device every MJWarp kernel runs its threads one after
the other, each world's solver stops on its own convergence flag (mujoco_warp solver.py, ``ctx.done[worldid]``),
and a world's values are read from its own rows, so nothing of another world enters a world's arithmetic. A
difference of any size would mean the batch is not the single-world engine (what this file guards).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mujoco_warp")

from backends.base import Backend  # noqa: E402
from backends.batch import WorldBatch  # noqa: E402
from backends.errors import EngineFailure  # noqa: E402
from backends.registry import create_backend, get_backend  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.types import CompiledWorld, Motor, Surface  # noqa: E402

BOX = (0.2, 0.2, 0.2)
STEPS = 120  # 1.2 s at dt 0.01: the 1 m drop lands at ~0.41 s, bounces, and the boxes come to rest


def drop(density: float, z0: float, bounce: float, *, dt: float = 0.01) -> CompiledWorld:
    """A 0.2 m box dropped on the ground plane."""
    box = w.box("box", BOX, (0.0, 0.0, z0), density=density)
    return w.world("drop", [w.ground(), box], dt=dt, surface=Surface(bounce=bounce, mu=1.0))


def eight_drops() -> list[CompiledWorld]:
    """mass (1 and 4 kg... 8 and 32 kg: density 500 / 2000) x start height x bounce."""
    return [drop(d, z, b) for d in (500.0, 2000.0) for z in (0.5, 1.0) for b in (0.0, 0.5)]


def batch_class() -> type[WorldBatch]:
    cls = get_backend("mujoco_warp").world_batch()
    assert cls is not None
    return cls


def state(sim: object) -> np.ndarray:
    s = sim.body_states()  # type: ignore[attr-defined]
    return np.hstack([s.pos, s.quat, s.lin_vel, s.ang_vel])


def run_alone(world: CompiledWorld, steps: int) -> tuple[np.ndarray, list]:
    return run_alone_with_settings(world, steps)[:2]


def run_alone_with_settings(world: CompiledWorld, steps: int) -> tuple[np.ndarray, list, dict]:
    with create_backend("mujoco_warp", world) as sim:
        settings = sim.settings()
        for _ in range(steps):
            sim.step()
        return state(sim), sim.contacts(), settings


# --- why_not ----------------------------------------------------------------------------------------------


def test_worlds_differing_in_mass_start_height_and_bounce_make_one_batch() -> None:
    assert batch_class().why_not(eight_drops()) is None


def test_a_different_body_count_is_refused_naming_the_size() -> None:
    two = w.world("drop", [w.ground(), w.box("a", BOX, (0, 0, 1.0)), w.box("b", BOX, (1, 0, 1.0))])
    reason = batch_class().why_not([drop(500.0, 1.0, 0.0), two])
    assert reason is not None and "nbody" in reason and "variant 1" in reason and "variant 0" in reason


def test_a_different_shape_is_refused_naming_the_field() -> None:
    ball = w.world("drop", [w.ground(), w.sphere("box", 0.1, (0, 0, 1.0))], surface=Surface(bounce=0.0, mu=1.0))
    reason = batch_class().why_not([drop(500.0, 1.0, 0.0), ball])
    assert reason is not None and "geom_type" in reason


def test_a_different_dt_is_refused() -> None:
    reason = batch_class().why_not([drop(500.0, 1.0, 0.0), drop(500.0, 1.0, 0.0, dt=0.005)])
    assert reason is not None and "world.dt is 0.005 in variant 1 and 0.01 in variant 0" in reason


def test_a_different_gravity_is_refused_as_an_option() -> None:
    moon = dataclasses.replace(drop(500.0, 1.0, 0.0), gravity=(0.0, 0.0, -1.62))
    reason = batch_class().why_not([drop(500.0, 1.0, 0.0), moon])
    assert reason is not None and "opt.gravity" in reason


def test_a_different_friction_is_per_world() -> None:
    icy = dataclasses.replace(drop(500.0, 1.0, 0.0), default_surface=Surface(bounce=0.0, mu=0.1))
    assert batch_class().why_not([drop(500.0, 1.0, 0.0), icy]) is None


# --- the same worlds, batched or alone --------------------------------------------------------------------


def test_each_world_of_a_batch_is_that_world_run_alone() -> None:
    worlds = eight_drops()
    assert batch_class().why_not(worlds) is None  # as a sweep does: the batch then takes the worlds it built
    with batch_class()(worlds) as batch:
        settings = [v.settings() for v in batch.views]  # what the trace records of the engine
        for _ in range(STEPS):
            assert batch.step_all([True] * len(worlds)) == {}
            for view in batch.views:
                view.step()
        batched = [(state(v), v.contacts()) for v in batch.views]
    for k, world in enumerate(worlds):
        alone, contacts, alone_settings = run_alone_with_settings(world, STEPS)
        assert np.array_equal(batched[k][0], alone), f"world {k}: {np.abs(batched[k][0] - alone).max()}"
        assert batched[k][1] == contacts, f"world {k}"
        assert settings[k] == alone_settings, f"world {k}"
    # the per-world fields reached the engine: at rest the ground carries each box's weight. Tolerance: the
    # contact rows' impedance 0.999 lets 0.1 % of the unconstrained acceleration through (backends/mujoco/_geoms.py)
    for k, world in enumerate(worlds):
        if world.default_surface.bounce:
            continue  # the bouncing 1 m drop is still in the air at 1.2 s
        weight = world.bodies[1].mass * w.G
        force = sum(c.normal_force for c in batched[k][1])
        assert force == pytest.approx(weight, rel=2e-3), f"world {k}"
    # and the bounce did: the 1 m drop with bounce 0.5 rose again, the one with bounce 0 did not (checked alone)
    assert not math.isclose(batched[2][0][1, 2], batched[3][0][1, 2])


def test_inputs_go_to_their_own_world() -> None:
    """A force and a reset given to one view act on its world only, as on that world alone."""
    worlds = [drop(500.0, 1.0, 0.0), drop(500.0, 1.0, 0.0)]
    with batch_class()(worlds) as batch:
        a, b = batch.views
        for step in range(30):
            if step == 5:
                a.apply_force(1, (50.0, 0.0, 0.0), (0.0, 0.0, 0.0))
            if step == 10:
                b.reset_body(1, (0.0, 0.0, 0.6), (1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
            batch.step_all([True, True])
            a.step()
            b.step()
        got = [state(a), state(b)]
    with create_backend("mujoco_warp", worlds[0]) as sim:
        for step in range(30):
            if step == 5:
                sim.apply_force(1, (50.0, 0.0, 0.0), (0.0, 0.0, 0.0))
            sim.step()
        assert np.array_equal(got[0], state(sim))
    with create_backend("mujoco_warp", worlds[1]) as sim:
        for step in range(30):
            if step == 10:
                sim.reset_body(1, (0.0, 0.0, 0.6), (1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
            sim.step()
        assert np.array_equal(got[1], state(sim))


def test_a_view_steps_only_after_step_all() -> None:
    with batch_class()([drop(500.0, 1.0, 0.0)]) as batch:
        with pytest.raises(RuntimeError, match="not stepped by step_all"):
            batch.views[0].step()


def _launched(mu: float, z0: float = 0.0999) -> CompiledWorld:
    """A 0.2 m box launched along x at 1 m/s on the ground (mu): it slides to a stop after 1/(2 mu g)."""
    box = dataclasses.replace(w.box("box", BOX, (0.0, 0.0, z0), density=500.0), lin_vel=(1.0, 0.0, 0.0))
    return w.world("slide", [w.ground(), box], dt=0.01, surface=Surface(bounce=0.0, mu=mu))


def test_sliding_worlds_correct_their_friction_each_alone() -> None:
    """The Coulomb correction iterates each world's solves to its own test (backends/mujoco_warp/_corrections.py):
    worlds sliding on different mu, and one in the air, end as each does alone, bit for bit; the slides' speeds
    are Coulomb's, v0 - mu g t, within float32 (2 x 30 velocity updates rounded to 2^-24 of 1 m/s: 4e-6) and the
    contact rows' impedance (0.999: 1e-3 of mu g t leaks through, at most 3e-4 m/s at 0.3 s)."""
    worlds = [_launched(0.1), _launched(0.3), _launched(0.3, z0=2.0)]
    steps = 30
    with batch_class()(worlds) as batch:
        for _ in range(steps):
            assert batch.step_all([True] * len(worlds)) == {}
            for view in batch.views:
                view.step()
        batched = [state(v) for v in batch.views]
    for k, world in enumerate(worlds[:2]):
        alone, _ = run_alone(world, steps)
        assert np.array_equal(batched[k], alone), f"world {k}: {np.abs(batched[k] - alone).max()}"
        mu = world.default_surface.mu
        expected = 1.0 - mu * w.G * steps * world.dt
        assert batched[k][1, 7] == pytest.approx(expected, abs=4e-6 + 1e-3 * mu * w.G * steps * world.dt)
    assert np.array_equal(batched[2], run_alone(worlds[2], steps)[0])


# --- failures, per world ------------------------------------------------------------------------------------


def _row(z0: float) -> CompiledWorld:
    """Four boxes side by side at height z0; a contact buffer of 1 per body + 8 = 13 < their 16 on the ground."""
    boxes = [w.box(f"b{i}", BOX, (0.5 * i, 0.0, z0)) for i in range(4)]
    world = w.world("row", [w.ground(), *boxes], dt=0.01)
    return dataclasses.replace(world, backend_options={"mujoco_warp": {"contacts_per_body": 1}})


def _failing_step(world: CompiledWorld, steps: int) -> int | None:
    """The step (1-based) in which ``world`` run alone fails, or None."""
    with create_backend("mujoco_warp", world) as sim:
        for k in range(1, steps + 1):
            try:
                sim.step()
            except EngineFailure:
                return k
    return None


def test_a_world_that_fills_its_contact_buffer_fails_alone() -> None:
    landing, high = _row(0.1), _row(5.0)  # the first rests on the ground from the start; the second is in the air
    fails_at = _failing_step(landing, 5)
    assert fails_at is not None and _failing_step(high, 5) is None
    high_alone, _ = run_alone(high, 5)
    with batch_class()([landing, high]) as batch:
        wide, other = batch.views
        for k in range(1, fails_at + 1):
            failures = batch.step_all([True, True])
            other.step()
            if k < fails_at:
                assert failures == {}
                wide.step()
        assert set(failures) == {0} and "contact buffer (13 contacts)" in str(failures[0])
        with pytest.raises(EngineFailure, match="contact buffer"):
            wide.step()
        for _ in range(fails_at, 5):  # the runner has ended world 0's session
            assert batch.step_all([False, True]) == {}
            other.step()
        assert np.array_equal(state(other), high_alone)


def test_a_blown_up_world_leaves_the_others_as_they_would_be_alone() -> None:
    worlds = [drop(500.0, 1.0, 0.5), drop(500.0, 0.5, 0.0)]
    with batch_class()(worlds) as batch:
        wild, calm = batch.views
        wild.reset_body(1, (0.0, 0.0, 0.5), (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, -1e30), (0.0, 0.0, 0.0))
        active = [True, True]
        for _ in range(STEPS):
            assert batch.step_all(active) == {}
            if active[0]:
                wild.step()
                if not np.isfinite(state(wild)).all() or np.abs(state(wild)).max() > 1e4:
                    active[0] = False  # the runner ends a blown-up world's session (runner.sim.session)
            calm.step()
        assert not active[0]
        calm_state = state(calm)
    alone, _ = run_alone(worlds[1], STEPS)
    assert np.array_equal(calm_state, alone)


# --- worlds with host work in every step: motors, kinematic bodies, substeps, watched joints ----------------


def _door(fmax: float) -> CompiledWorld:
    return w.lab_door(lo=-0.1, hi=0.1, motor=Motor(0.3, fmax))


def _scripted(sim: Backend, k: int, world: int) -> None:
    """Inputs the runner would give: world 1's motor is retargeted and switched off; world 0's box kicked."""
    if world == 1 and k == 10 and sim.world.name == "door":
        sim.set_motor(0, -0.3, 50.0)
    if world == 1 and k == 20 and sim.world.name == "door":
        sim.set_motor(0, 0.0, 0.0)
    if world == 0 and k == 5 and sim.world.name == "kick":
        sim.apply_force(0, (0.0, 0.0, 1000.0), (0.0, 0.0, 0.0))


def _reads(sim: Backend) -> list[object]:
    return [state(sim), sim.joint_states(), sim.contacts(), sim.contact_points()] + (
        [sim.joint_reactions()] if sim.world.reaction_joints else []
    )


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray):
        return bool(np.array_equal(a, b, equal_nan=True))
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return bool(a == b)


@pytest.mark.parametrize(
    "pair",
    [
        pytest.param((_door(100.0), _door(400.0)), id="motors"),
        pytest.param((w.kinematic_platform(), w.kinematic_platform()), id="kinematic"),
        pytest.param((w.lab_kick(substeps=3), w.lab_kick(substeps=3)), id="substeps"),
        pytest.param(
            tuple(
                dataclasses.replace(w.offset_hinge(lo=-0.5, hi=0.5), substeps=2, reaction_joints=("hinge",))
                for _ in range(2)
            ),
            id="reactions",
        ),  # fmt: skip
    ],
)
def test_worlds_with_host_work_are_those_worlds_alone(pair: tuple[CompiledWorld, CompiledWorld]) -> None:
    steps = 30
    with batch_class()(pair) as batch:
        got: list[list[list[object]]] = [[], []]
        for k in range(steps):
            for i, view in enumerate(batch.views):
                _scripted(view, k, i)
            assert batch.step_all([True, True]) == {}
            for i, view in enumerate(batch.views):
                view.step()
                got[i].append(_reads(view))
    for i, world in enumerate(pair):
        with create_backend("mujoco_warp", world) as sim:
            for k in range(steps):
                _scripted(sim, k, i)
                sim.step()
                assert _same(got[i][k], _reads(sim)), f"world {i}, step {k + 1}"
