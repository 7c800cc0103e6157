"""One engine step that holds joint couplings (``joint:mimic``), solved by Newton steps on trial steps.

A coupling ``q_f = m q_l + c`` is held in a step by one term ``u`` per coupling that the engine applies for the
step (DART: a shift of its coupler's offset; ODE: the force pair +u on the follower's coordinate, -m u on the
leader's). After the step the coupling's rate residual ``r = v_f' - m v_l' - (m q_l + c - q_f) / h`` (error
reduction 1 from the start-of-step positions) must vanish. The step is affine in ``u`` while its set of active
constraints (contacts, stops) stays, so from a first ``u`` the residuals of a trial step, a slope measured by
one nudged trial per coupling, and ``u -= slope^-1 r`` reach the root in one Newton step; a few more absorb a
change of active set. Every trial starts from the step's start (``trial`` restores the engine's state itself);
the kept step is the last trial taken.

The slope is taken per nudge and per the rate change each nudge is expected to make (``nudge`` gives both), so
that a free coupling's column is of order 1 whatever the units. Its singular values below ``rcond`` (a coupled
joint that contacts or stops lock, so that no ``u`` moves its residual) are left out: the step is the
least-squares one on the resolved directions (the minimum-norm change): the locked term stays, the others make
the residuals as small as they can. If no trial meets the tolerance, the trial with
the smallest residual (relative to each coupling's tolerance) is taken again and returned with ``held`` False:
the caller raises or warns.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CoupledStep:
    """The kept step: its terms, the rate residuals it left, whether each is within tolerance, its slope."""

    terms: np.ndarray
    residual: np.ndarray
    held: bool
    slope: np.ndarray | None  # the last slope (None: none was needed), for the next step's first try


def solve_coupled_step(
    trial: Callable[[np.ndarray], np.ndarray],
    start: np.ndarray,
    nudge: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    tolerance: np.ndarray,
    h: float,
    iterations: int,
    rcond: float,
    slope: np.ndarray | None = None,
    remeasure: bool = True,
) -> CoupledStep:
    """Take the engine step whose terms hold every coupling: ``h |r_k| <= tolerance_k`` (module docstring).

    ``trial(u)`` restores the step's start, takes the step with the terms ``u`` and returns the rate residuals.
    ``start``: the first terms tried; ``nudge(r)``: each term's finite-difference step for a slope measured where
    the residuals are ``r``, and the change of its coupling's rate residual it is expected to make; ``slope``: a
    slope from an earlier step, tried first. ``remeasure``: each later Newton step measures its own slope (n more
    trials); else the slope is carried by Broyden's update from the trials themselves (one trial per Newton
    step), and measured only when none is known or two Newton steps in a row fail to halve the residual.
    """
    u = np.array(start, dtype=float)
    residual = trial(u)
    best = (_score(residual, tolerance, h), u.copy())
    measure = slope is None
    stalls = 0
    for _ in range(iterations):
        if _held(residual, tolerance, h):
            return CoupledStep(u, residual, True, slope)
        steps, rates = nudge(residual)
        if measure or slope is None or stalls >= 2:
            slope, stalls = _measure(trial, u, residual, steps), 0
        measure = remeasure
        scale = steps / rates
        change = -scale * _newton_step(slope * scale, residual, rcond)
        new = trial(u + change)
        if not remeasure and float(change @ change) > 0.0:  # Broyden: the slope that explains this trial
            slope = slope + np.outer(new - residual - slope @ change, change) / float(change @ change)
        stalls = stalls + 1 if np.max(np.abs(new)) > 0.5 * np.max(np.abs(residual)) else 0
        u, residual = u + change, new
        score = _score(residual, tolerance, h)
        if score < best[0]:
            best = (score, u.copy())
    if _held(residual, tolerance, h):
        return CoupledStep(u, residual, True, slope)
    if not np.array_equal(best[1], u):  # the smallest residual was an earlier trial: keep that step
        u = best[1]
        residual = trial(u)
    return CoupledStep(u, residual, False, slope)


def _held(residual: np.ndarray, tolerance: np.ndarray, h: float) -> bool:
    return bool(np.all(h * np.abs(residual) <= tolerance))


def _score(residual: np.ndarray, tolerance: np.ndarray, h: float) -> float:
    """The worst coupling's miss in units of its tolerance (NaN counts as the worst)."""
    ratios = h * np.abs(residual) / tolerance
    return float(np.max(ratios)) if np.all(np.isfinite(ratios)) else float("inf")


def _measure(
    trial: Callable[[np.ndarray], np.ndarray], u: np.ndarray, residual: np.ndarray, nudge: np.ndarray
) -> np.ndarray:
    """The residuals' slope against each term at ``u``: one trial per term, nudged by its ``nudge``."""
    n = len(u)
    slope = np.empty((n, n))
    for k in range(n):
        nudged = u.copy()
        nudged[k] += nudge[k]
        slope[:, k] = (trial(nudged) - residual) / nudge[k]
    return slope


def _newton_step(slope: np.ndarray, residual: np.ndarray, rcond: float) -> np.ndarray:
    """``slope^-1 residual`` (the slope per expected rate change: a free coupling's column of order 1), or, where
    singular values fall below ``rcond``, the least-squares solution on the others (the minimum-norm change: the
    locked couplings' terms are left where they are)."""
    if not np.all(np.isfinite(slope)):
        return np.zeros_like(residual)
    left, values, right = np.linalg.svd(slope)
    if values[-1] > rcond:
        return np.linalg.solve(slope, residual)
    kept = values > rcond
    return right[kept].T @ ((left[:, kept].T @ residual) / values[kept])
