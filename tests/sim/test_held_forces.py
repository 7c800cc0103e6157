"""The runner's held forces (`apply`, runner/sim/held.py): how many steps one acts, when `until` stops it, and
how `frame: body` and `at` turn into a world force and torque (docs/semantics.md, "Held forces"). The
engines' side (every substep feels the force) is the contract suite's and conformance case 18's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from runner.language.model_actions import ApplyCommand
from runner.sim.held import HeldForces

STILL = np.array([[1.0, 0.0, 0.0, 0.0]])


def _steps(held: HeldForces, quats: np.ndarray = STILL, truth=lambda text: False) -> int:  # noqa: ANN001
    count = 0
    while held and count < 1000:
        count += len(held.step_inputs(quats, truth))
    return count


@pytest.mark.parametrize(("seconds", "steps"), [(0.09, 3), (0.1, 3), (0.001, 1), (0.3, 10)])
def test_for_lasts_whole_steps_at_least_one(seconds: float, steps: int) -> None:
    held = HeldForces(0.03, [(0.0, 0.0, 0.0)])
    held.start(0, ApplyCommand(body="b", force=(0.0, 0.0, 1.0), **{"for": seconds}))
    assert _steps(held) == steps  # round(seconds / dt), at least 1


def test_until_is_checked_before_each_step_the_first_included() -> None:
    held = HeldForces(0.01, [(0.0, 0.0, 0.0)])
    held.start(0, ApplyCommand(body="b", force=(1.0, 0.0, 0.0), until="state.done"))
    assert held.step_inputs(STILL, lambda text: True) == []  # true at once: never applied
    assert not held
    held.start(0, ApplyCommand(body="b", force=(1.0, 0.0, 0.0), until="state.done"))
    answers = iter([False, False, True])
    assert _steps(held, truth=lambda text: next(answers)) == 2


def test_body_frame_and_a_point_turn_with_the_body() -> None:
    """A body turned 90 degrees about z (body x is world y), its centre of mass at (0.1, 0, 0) in its frame:
    the force (2, 0, 0) in the body frame is (0, 2, 0) in the world, the torque (0, 0, 1) stays, and the
    force at the body point (0.1, 0.5, 0) adds R (at - com) x F = (-0.5, 0, 0) x (0, 2, 0) = (0, 0, -1)."""
    turn = np.array([[math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]])
    held = HeldForces(0.01, [(0.1, 0.0, 0.0)])
    held.start(0, ApplyCommand(body="b", force=(2.0, 0.0, 0.0), torque=(0.0, 0.0, 1.0), frame="body",
                               at=(0.1, 0.5, 0.0), **{"for": 0.01}))  # fmt: skip
    [(body, force, torque)] = held.step_inputs(turn, lambda text: False)
    assert body == 0
    assert force == pytest.approx((0.0, 2.0, 0.0), abs=1e-15)
    assert torque == pytest.approx((0.0, 0.0, 0.0), abs=1e-15)  # 1 from the torque, -1 from the point


def test_world_frame_forces_do_not_turn_and_several_add_in_order() -> None:
    turn = np.array([[math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]] * 2)
    held = HeldForces(0.01, [(0.0, 0.0, 0.0)] * 2)
    held.start(1, ApplyCommand(body="b", force=(3.0, 0.0, 0.0), **{"for": 0.02}))
    held.start(0, ApplyCommand(body="a", torque=(0.0, 1.0, 0.0), **{"for": 0.01}))
    first = held.step_inputs(turn, lambda text: False)
    assert [(b, f.tolist(), t.tolist()) for b, f, t in first] == [(1, [3.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
                                                                  (0, [0.0, 0.0, 0.0], [0.0, 1.0, 0.0])]  # fmt: skip
    assert [b for b, _, _ in held.step_inputs(turn, lambda text: False)] == [1]
    assert not held
