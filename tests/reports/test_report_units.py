"""Unit tests of the report's parts: GIF encoding, orientation error, alignment, pictures, charts, audio."""

from __future__ import annotations

import math

import numpy as np
import pytest

from backends.geometry import quat_from_axis_angle, quat_mul
from reports import divergence as dv
from reports.audio import decode_wav, encode_wav, mix_sounds
from reports.events_data import match_times
from reports.gif import encode_gif
from reports.pictures import fit_view, scene_faces, svg_picture
from reports.plots import Series, line_chart, nice_ticks
from reports.trace_reader import SoundRecord

from .gif_decode import decode_gif


def test_gif_round_trip_with_delta_frames_and_merged_repeats() -> None:
    rng = np.random.default_rng(7)
    base = rng.integers(0, 5, size=(40, 60), dtype=np.uint8)
    moved = base.copy()
    moved[10:14, 20:31] = 4  # a small change: stored as a 4 x 11 patch
    frames = [base, moved, moved.copy(), base]
    data = encode_gif(frames, [(0, 0, 0), (255, 0, 0), (0, 255, 0), (0, 0, 255), (9, 9, 9)], delay_cs=10)
    decoded, delays, palette = decode_gif(data)
    assert len(decoded) == 3  # the repeated frame became a longer delay
    assert delays == [10, 20, 10]
    for got, want in zip(decoded, [base, moved, base], strict=True):
        assert np.array_equal(got, want)
    assert palette[:5] == [(0, 0, 0), (255, 0, 0), (0, 255, 0), (0, 0, 255), (9, 9, 9)]


def test_gif_lzw_survives_a_full_code_table() -> None:
    """Noise over 255 colours fills the 4096-entry table many times: clear codes and 12-bit codes."""
    rng = np.random.default_rng(1)
    frame = rng.integers(0, 255, size=(120, 200), dtype=np.uint8)
    palette = [(i, 255 - i, (7 * i) % 256) for i in range(255)]
    decoded, _, _ = decode_gif(encode_gif([frame], palette, delay_cs=5))
    assert np.array_equal(decoded[0], frame)


def test_gif_refuses_a_palette_without_room_for_transparency() -> None:
    with pytest.raises(ValueError, match="1 to 255"):
        encode_gif([np.zeros((2, 2), np.uint8)], [(0, 0, 0)] * 256, 10)


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


def _spec(name: str, shape: dict, motion: str = "dynamic") -> dict:
    return {"name": name, "motion": motion, "shape": {"size": [0, 0, 0], "radius": 0, "length": 0, **shape},
            "color": [0.5, 0.5, 0.5, 1.0]}  # fmt: skip


def test_pictures_cull_back_faces_and_draw_the_floor_first() -> None:
    specs = [_spec("box", {"kind": "box", "size": [1, 1, 1]}), _spec("ball", {"kind": "sphere", "radius": 0.5}),
             _spec("floor", {"kind": "plane"}, "static")]  # fmt: skip
    pos = np.array([[0.0, 0.0, 0.5], [2.0, 0.0, 0.5], [0.0, 0.0, 0.0]])
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (3, 1))
    view = fit_view([(specs, pos[None], quat[None])])
    faces = scene_faces(specs, pos, quat, view.centre, view.extent)
    assert faces[0].floor and sum(f.floor for f in faces) == 1
    # the camera looks from +x, -y, +z: a box shows exactly its +x, -y and +z faces; a sphere is one disc
    assert sum(f.radius == 0 and not f.floor for f in faces) == 3
    assert sum(f.radius > 0 for f in faces) == 1
    svg = svg_picture(faces, view, 200, "box & ball")
    assert svg.count("<polygon") == 4 and svg.count("<circle") == 1 and "box &amp; ball" in svg


def test_nice_ticks_and_chart_shape() -> None:
    assert nice_ticks(0.0, 6.0, 6) == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    assert nice_ticks(-0.013, 0.021, 4) == pytest.approx([-0.01, 0.0, 0.01, 0.02])
    svg = line_chart("z <m>", [Series("a", "#000", [0, 1, 2, 3], [0.0, 1.0, None, 2.0])])
    assert svg.startswith('<svg class="plot"') and "z &lt;m&gt;" in svg
    assert svg.count("<polyline") == 1 and svg.count("<circle") == 1  # the gap splits the series


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
