"""The runner's per-step blow-up check (runner.sim.blowup.blown_up): its quick path for the common case
(every state finite and within the speed limit) must agree with the exact per-body test everywhere."""

from __future__ import annotations

import numpy as np
import pytest

from backends.types import BodyStates
from runner.sim.blowup import MAX_SPEED, blown_up


def states(n: int = 5) -> BodyStates:
    rng = np.random.default_rng(7)
    quat = rng.normal(size=(n, 4))
    quat /= np.linalg.norm(quat, axis=1)[:, None]
    return BodyStates(rng.normal(size=(n, 3)), quat, rng.normal(size=(n, 3)), rng.normal(size=(n, 3)))


def test_finite_states_within_the_limit_pass() -> None:
    assert blown_up(states()) is None
    assert blown_up(BodyStates(np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 3)), np.zeros((0, 3)))) is None


@pytest.mark.parametrize("field", ["pos", "quat", "lin_vel", "ang_vel"])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_non_finite_value_anywhere_names_its_body(field: str, value: float) -> None:
    s = states()
    getattr(s, field)[3, 1] = value
    assert blown_up(s) == (3, True)


@pytest.mark.parametrize("field", ["lin_vel", "ang_vel"])
def test_the_speed_limit_is_inclusive_and_exact(field: str) -> None:
    s = states()
    getattr(s, field)[2] = (MAX_SPEED, 0.0, 0.0)  # exactly at the limit: not a blow-up
    assert blown_up(s) is None
    getattr(s, field)[2] = (0.0, np.nextafter(MAX_SPEED, np.inf), 0.0)  # the next double above it is
    assert blown_up(s) == (2, False)
    getattr(s, field)[2] = (0.6 * MAX_SPEED, 0.8 * MAX_SPEED, 0.0)  # |v| = MAX_SPEED up to rounding
    exact = bool(np.linalg.norm(getattr(s, field)[2]) > MAX_SPEED)
    assert blown_up(s) == ((2, False) if exact else None)


def test_huge_finite_values_whose_squares_overflow_are_speeds_not_nan() -> None:
    s = states()
    s.lin_vel[4] = (1e200, 0.0, 0.0)  # |v|^2 overflows to inf; the state itself is finite
    assert blown_up(s) == (4, False)
    s = states()
    s.pos[1] = (1e308, 1e308, 0.0)  # huge but finite positions are not a blow-up
    assert blown_up(s) is None


def test_the_first_bad_body_is_named() -> None:
    s = states()
    s.ang_vel[1] = (2 * MAX_SPEED, 0.0, 0.0)
    s.pos[3] = (np.nan, 0.0, 0.0)
    assert blown_up(s) == (1, False)
