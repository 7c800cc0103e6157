"""The audio track in the HTML report: the scenario's attached sounds mixed at their trigger times."""

from __future__ import annotations

import base64
import re

import numpy as np
import pytest

from reports.audio import decode_wav

from .conftest import ROOT, SoundReport

RATE = 22050  # scenarios/sounds/make_sounds.py


def test_each_backend_gets_a_wav_with_thud_at_the_collision(sound_report: SoundReport) -> None:
    html = (sound_report.out / "report.html").read_text(encoding="utf-8")
    pattern = r'<figcaption>([^<]+)</figcaption><audio [^>]*src="data:audio/wav;base64,([^"]+)"'
    tracks = dict(re.findall(pattern, html))
    assert sorted(tracks) == ["fake", "ode"]
    thud, rate = decode_wav((ROOT / "scenarios" / "sounds" / "thud.wav").read_bytes())
    assert rate == RATE
    for backend, data in tracks.items():
        mix, mix_rate = decode_wav(base64.b64decode(data))
        assert mix_rate == RATE and len(mix) == 8 * RATE, backend  # the run lasts 8 s
        # door-closed: the box's sphere touches the door at t = 2.16 s and the handler plays thud there
        start = round(2.16 * RATE)
        assert np.flatnonzero(mix)[0] == pytest.approx(start, abs=1)
        assert mix[start : start + len(thud)] == pytest.approx(thud, abs=2 / 32767)  # 16-bit round trip
        assert not mix[start + len(thud) :].any()  # the door never closes: close.wav does not play
