"""Unit tests of the report's parts: orientation error, alignment, statistics, audio, event matching."""

from __future__ import annotations

import math

import numpy as np
import pytest

from backends.geometry import quat_from_axis_angle, quat_mul
from reports import divergence as dv
from reports.audio import decode_wav, encode_wav, mix_sounds
from reports.events_data import match_times
from reports.trace_reader import SoundRecord


@pytest.mark.parametrize("angle", [0.0, 1e-4, 0.3, math.pi / 2, 3.0])
def test_orientation_error_is_the_rotation_angle(angle: float) -> None:
    base = quat_from_axis_angle((0.2, -0.5, 0.8), 0.7)
    turned = quat_mul(base, quat_from_axis_angle((1.0, 2.0, -0.5), angle))
    got = dv.quat_angle(np.array([base, base]), np.array([turned, [-c for c in turned]]))
    assert got == pytest.approx([angle, angle], abs=1e-9)  # and blind to the quaternion's sign


def test_alignment_uses_common_samples_or_interpolates() -> None:
    t = np.arange(0, 26) * 0.04
    same = dv.align(t[:10], t)
    assert np.array_equal(same.run_index, np.arange(10)) and np.array_equal(same.ref_index, np.arange(10))
    fine = np.arange(0, 51) * 0.02  # another dt: the reference is interpolated onto the run's times
    where = dv.align(fine, t)
    assert where.ref_index is None and where.times[-1] == pytest.approx(1.0)
    values = np.column_stack([t * 2.0, t * t])
    got = where.ref_values(values)
    assert got[:, 0] == pytest.approx(where.times * 2.0)
    assert got[1, 1] == pytest.approx(0.5 * (0.0 + 0.04**2))  # linear between samples


def test_stats_max_rms_and_first_time_over() -> None:
    t = np.array([0.0, 0.1, 0.2, 0.3])
    s = dv.stats(t, np.array([0.0, 0.02, 0.005, np.nan]), 0.01)
    assert s["max"] == 0.02 and s["max_time"] == 0.1 and s["first_over"] == 0.1
    assert s["rms"] == pytest.approx(math.sqrt((0.02**2 + 0.005**2) / 3))
    assert dv.stats(t, np.zeros(4), 0.01)["first_over"] is None


def test_audio_mix_places_each_sound_at_its_trigger_time() -> None:
    rate = 8000
    click = np.linspace(0.5, 0.0, 800)  # 0.1 s
    records = [SoundRecord(0.5, "click", "start", 0.0, 1.0), SoundRecord(1.25, "click", "start", 0.02, 0.5),
               SoundRecord(1.3, "click", "stop", 0.0, 1.0)]  # fmt: skip
    mixed = mix_sounds(records, {"click": (click, rate)}, end_time=2.0)
    assert mixed is not None
    out, got_rate = mixed
    assert got_rate == rate and len(out) == 2 * rate
    assert np.flatnonzero(out)[0] == 4000  # 0.5 s
    assert out[4000:4800] == pytest.approx(click)
    second = out[10000:10400]  # 1.25 s, from 0.02 s into the sound, half volume, stopped at 1.3 s
    assert second == pytest.approx(0.5 * click[160:560])
    assert not out[10400:].any()
    samples, r = decode_wav(encode_wav(out, rate))
    assert r == rate and samples == pytest.approx(out, abs=1 / 32767)


def test_event_matching_pairs_in_time_order_and_flags_extra_and_missing() -> None:
    ode = [1.0, 1.28, 3.04, 3.32, 3.92]
    other = [1.0, 1.28, 1.36, 3.04, 3.32]  # an extra bounce at 1.36 and no event at 3.92
    pairs = match_times(other, ode)
    assert pairs == [(0, 0), (1, 1), (3, 2), (4, 3)]
    assert match_times([2.0], [1.0]) == []  # further apart than the window: not the same occurrence
    assert match_times([1.04, 1.3], [1.0]) == [(0, 0)]
