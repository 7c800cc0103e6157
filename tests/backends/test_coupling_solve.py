"""The kit's Newton loop for coupled steps (backends/_kit/coupling_solve.py) on steps given in closed form.

An engine step is affine in the coupling terms while its active set stays: r(u) = r0 + S u. The loop must land
on the root in one Newton step (three trials: the first, one nudge per term... here two terms, so four), keep
the last trial as the step, leave a locked coupling (a zero column: contacts or stops take its force) out of
the Newton step instead of dividing by zero, and hand back the trial with the smallest residual, not held,
when none meets the tolerance. Tolerances: the residuals are exact in double precision up to the solve's
rounding, 1e-12 of their size.
"""

from __future__ import annotations

import numpy as np

from backends._kit.coupling_solve import solve_coupled_step

H = 0.002


class Step:
    """An affine 'engine step': records every trial, the last one being the state the engine is left in."""

    def __init__(self, r0: list[float], slope: list[list[float]]) -> None:
        self.r0, self.slope = np.array(r0), np.array(slope)
        self.trials: list[np.ndarray] = []

    def __call__(self, u: np.ndarray) -> np.ndarray:
        self.trials.append(u.copy())
        return self.r0 + self.slope @ u


def _nudge(residual: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.full(len(residual), 0.5), np.full(len(residual), 2.0)  # 0.5 of a term moves its rate by about 2


def test_an_affine_step_is_solved_by_one_newton_step_and_the_last_trial_is_kept() -> None:
    step = Step([0.3, -0.2], [[4.0, 1.0], [0.5, 3.0]])
    tolerance = np.full(2, 1e-12)
    solved = solve_coupled_step(step, np.zeros(2), _nudge, tolerance, H, 8, 1e-6)
    assert solved.held
    assert len(step.trials) == 4  # the first, two nudges, the Newton step
    assert np.array_equal(step.trials[-1], solved.terms)
    assert np.allclose(solved.terms, np.linalg.solve(step.slope, -step.r0), rtol=1e-12, atol=0)
    assert solved.slope is not None and np.allclose(solved.slope, step.slope, rtol=1e-12, atol=1e-12)


def test_a_known_slope_is_tried_first() -> None:
    step = Step([0.3, -0.2], [[4.0, 1.0], [0.5, 3.0]])
    solved = solve_coupled_step(step, np.zeros(2), _nudge, np.full(2, 1e-12), H, 8, 1e-6, slope=step.slope)
    assert solved.held and len(step.trials) == 2  # the first and the Newton step: no slope measured


def test_a_locked_coupling_is_left_out_and_reported_not_held() -> None:
    """Coupling 2's term moves nothing (its column 0): the locked term is left at 0 (the minimum-norm step), the
    free one makes both residuals as small as it can (least squares: u1 = -(4 x 0.3 + 0.5 x 0.1) / (4^2 + 0.5^2)),
    and the solve says it did not hold."""
    step = Step([0.3, 0.1], [[4.0, 0.0], [0.5, 0.0]])
    solved = solve_coupled_step(step, np.zeros(2), _nudge, np.full(2, 1e-12), H, 3, 1e-6)
    assert not solved.held
    assert solved.terms[1] == 0.0
    best = -(4.0 * 0.3 + 0.5 * 0.1) / (4.0**2 + 0.5**2)
    assert abs(solved.terms[0] - best) <= 1e-12 * abs(best)
    assert np.array_equal(step.trials[-1], solved.terms)  # the engine is left in the kept step


def test_without_remeasuring_the_slope_is_carried_by_broydens_update() -> None:
    """``remeasure=False`` (ODE's): a slope known from an earlier step but off (the contacts changed) is corrected
    from the trials themselves, with no nudged trial; Broyden's method ends on an affine map of n terms in at most
    2n steps, so within ITERATIONS = 8 for n = 2."""
    step = Step([0.3, -0.2], [[4.0, 1.0], [0.5, 3.0]])
    stale = np.array([[3.0, 0.0], [0.0, 2.0]])
    solved = solve_coupled_step(step, np.zeros(2), _nudge, np.full(2, 1e-12), H, 8, 1e-6, stale, remeasure=False)
    assert solved.held
    assert len(step.trials) <= 1 + 4  # the first and at most 2n Broyden steps: no nudge
    assert np.array_equal(step.trials[-1], solved.terms)
