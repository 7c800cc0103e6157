"""The energy watchdog evaluates its steps in blocks (runner.sim.energy, ``BLOCK_STEPS``): the verdict, the
time, the body, the joules and the last good state are those of a step-by-step check (a block of 1), whatever
the block; only when the gain is found moves, to the block's end, and a failure of another kind in the same
block (a blow-up, an interruption) never hides a gain that came before it.

The case is tests/sim/test_energy.py's: a 1 kg ball dropped from 1 m at dt = 0.01 s onto a floor that
doubles its speed (restitution 2, the engine fault): semi-implicit Euler puts it below the floor first at
step 45 (z_n = H0 - g dt^2 n (n + 1) / 2), and the gain is 3 K there, far beyond the bound.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from backends.types import BodyStates
from runner.sim import energy as energy_module
from runner.sim.energy import BodyEnergy
from runner.sim.session import RunResult
from tests.sim.test_energy import DROP, DT, H0, BouncingBackend, G, bouncing, run

#: the first step whose end the floor turns around (test_energy.py)
IMPACT = next(n for n in range(1, 1000) if H0 - G * DT**2 * n * (n + 1) / 2 < 0)
#: block sizes around the impact: one step at a time, blocks ending before, at and after it, longer than it
BLOCKS = [1, 2, 7, IMPACT, 25, 60, 400]


def failure_of(result: RunResult) -> tuple[Any, ...]:
    return (
        result.status,
        result.failure,
        result.extra.get("time"),
        result.extra.get("body"),
        result.extra.get("last_good"),
    )


def run_with_block(
    block: int, tmp_path: Path, backend: type, monkeypatch: pytest.MonkeyPatch, text: str = DROP
) -> RunResult:
    monkeypatch.setattr(energy_module, "BLOCK_STEPS", block)
    return run(tmp_path, text, backend, monkeypatch)


@pytest.mark.parametrize("block", BLOCKS)
def test_a_block_finds_the_gain_a_step_by_step_check_finds(
    block: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    one = run_with_block(1, tmp_path, bouncing(2.0), monkeypatch)
    blocked = run_with_block(block, tmp_path, bouncing(2.0), monkeypatch)
    assert one.status == "engine-failure" and one.extra["time"] == pytest.approx(IMPACT * DT)
    assert failure_of(blocked) == failure_of(one)


@pytest.mark.parametrize("block", BLOCKS)
@pytest.mark.parametrize("e", [0.0, 0.9, 1.0])
def test_a_block_passes_what_a_step_by_step_check_passes(
    block: int, e: float, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert run_with_block(block, tmp_path, bouncing(e), monkeypatch).status == "passed"


@pytest.mark.parametrize("block", [25, 400])
def test_a_gain_in_the_run_s_last_steps_is_found_at_its_end(
    block: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The run ends two steps after the impact, before any block is full: the end evaluates what is left."""
    text = DROP.replace("duration: 3", f"duration: {(IMPACT + 2) * DT}")
    result = run_with_block(block, tmp_path, bouncing(2.0), monkeypatch, text)
    assert result.status == "engine-failure" and result.extra["time"] == pytest.approx(IMPACT * DT)


class BlowingUp(BouncingBackend):
    """Doubles the speed at the floor, then, two steps later, either reports a non-finite state (a blow-up the
    runner finds) or is interrupted (Ctrl-C during the step)."""

    restitution = 2.0
    then = "nan"

    def _step(self) -> None:
        super()._step()
        if self.steps + 1 == IMPACT + 2:  # the step being taken (``steps`` counts those done)
            if self.then == "nan":
                self.vel[:] = np.nan
            else:
                raise KeyboardInterrupt


@pytest.mark.parametrize("then", ["nan", "interrupt"])
@pytest.mark.parametrize("block", [1, 25])
def test_a_gain_before_another_failure_is_the_one_reported(
    then: str, block: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    backend = type("Then", (BlowingUp,), {"then": then})
    result = run_with_block(block, tmp_path, backend, monkeypatch)
    assert result.status == "engine-failure"
    assert result.failure is not None and result.failure.startswith("energy gain: body `ball`")
    assert result.extra["time"] == pytest.approx(IMPACT * DT)
    assert result.extra["last_good"]["vel"][2] < 0  # the step before the impact: still falling


def test_without_a_gain_the_other_failure_is_reported(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    backend = type("Then", (BlowingUp,), {"then": "nan", "restitution": 0.5})
    result = run_with_block(25, tmp_path, backend, monkeypatch)
    assert result.status == "engine-failure" and result.failure is not None
    assert "non-finite state" in result.failure and result.extra["time"] == pytest.approx((IMPACT + 2) * DT)


@pytest.mark.parametrize("bodies", [1, 8, 40])
def test_a_block_s_energies_are_each_step_s(bodies: int) -> None:
    """The block's whole-array calls on (K, N) states against the same calls on each step's (N) states: the same
    products and sums, in the same order per element; numpy may order a batched product's terms otherwise, so
    they agree to rounding: 4 N eps of the sum of the terms' magnitudes (the watchdog's own rounding term)."""
    rng = np.random.default_rng(bodies)
    k = 25
    quat = rng.normal(size=(k, bodies, 4))
    quat /= np.linalg.norm(quat, axis=-1, keepdims=True)
    pos, v, w = (rng.normal(size=(k, bodies, 3)) for _ in range(3))
    mass = rng.uniform(0.1, 10, bodies)
    inertia = rng.uniform(0.01, 1, (bodies, 3))
    com = rng.normal(scale=0.2, size=(bodies, 3))
    axes = np.linalg.qr(rng.normal(size=(bodies, 3, 3)))[0]
    tensor = axes @ (inertia[:, :, None] * np.transpose(axes, (0, 2, 1)))
    for c, t in ((None, None), (com, None), (com, tensor)):
        model = BodyEnergy(slice(None), mass, inertia, np.array([0.0, 0.0, -G]), c, t)
        kinetic, total = model.of_arrays(quat, w, pos, v)
        for step in range(k):
            one_k, one_total = model(BodyStates(pos[step], quat[step], v[step], w[step]))
            scale = 4 * bodies * np.finfo(float).eps * (np.abs(one_total).sum() + np.abs(one_k).sum())
            assert np.abs(kinetic[step] - one_k).max() <= scale
            assert np.abs(total[step] - one_total).max() <= scale
