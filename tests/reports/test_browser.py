"""The HTML report in a real headless Chromium (Debian's `chromium`), loaded from a file:// URL.

Checks: no console error or warning, no uncaught exception, no failed load and no request other than
file: and data:; the plots, pictures and the animation are present and decode; the audio track decodes
to the run's length; a full-page screenshot is taken. About 5 s. Skipped only when no Chromium is
installed (CI installs it: apt-get install chromium); with SCENARIO_REQUIRE_BROWSER=1 (set by .ci/run) a
missing browser fails instead.
"""

from __future__ import annotations

import base64
import os
from pathlib import Path
from typing import Any

import pytest

from .cdp import Browser, find_chromium
from .conftest import CompareRun, SoundReport

CHROMIUM = find_chromium()
REQUIRED = os.environ.get("SCENARIO_REQUIRE_BROWSER") == "1"
pytestmark = pytest.mark.skipif(
    CHROMIUM is None and not REQUIRED, reason="no Chromium on this machine (apt-get install chromium)"
)

PROBE = """(async () => {
  const imgs = [...document.querySelectorAll('img')];
  await Promise.all(imgs.map(i => i.decode().catch(() => null)));
  const audio = document.querySelector('audio');
  let audioDuration = null;
  if (audio) {
    audioDuration = await new Promise(done => {
      const a = new Audio();
      a.addEventListener('loadedmetadata', () => done(a.duration));
      a.addEventListener('error', () => done(-1));
      setTimeout(() => done(-2), 10000);
      a.src = audio.src;
    });
  }
  const data = JSON.parse(document.getElementById('report-data').textContent);
  const size = el => { const r = el.getBoundingClientRect(); return [r.width, r.height]; };
  return {
    plots: [...document.querySelectorAll('svg.plot')].map(size),
    pictures: [...document.querySelectorAll('svg.picture')].map(size),
    images: imgs.map(i => [i.naturalWidth, i.naturalHeight, i.complete]),
    audios: document.querySelectorAll('audio').length,
    audioDuration,
    cases: data.cases.length,
    title: document.title,
  };
})()"""


def _load(page: Path, tmp_path: Path) -> tuple[dict[str, Any], list[str], Path]:
    if CHROMIUM is None:
        pytest.fail("SCENARIO_REQUIRE_BROWSER=1 but no Chromium is installed (apt-get install chromium)")
    browser = Browser(CHROMIUM, tmp_path / "profile")
    try:
        for domain in ("Page", "Runtime", "Log", "Network"):
            browser.call(f"{domain}.enable")
        browser.call("Page.navigate", url=page.resolve().as_uri())
        browser.wait_for("Page.loadEventFired")
        found = browser.evaluate(PROBE)
        metrics = browser.call("Page.getLayoutMetrics")
        height = int(min(metrics["cssContentSize"]["height"], 16000))
        browser.call("Emulation.setDeviceMetricsOverride", width=1400, height=height, deviceScaleFactor=1, mobile=False)
        shot = browser.call("Page.captureScreenshot", format="png", captureBeyondViewport=True)
        png = tmp_path / f"{page.parent.name}.png"
        png.write_bytes(base64.b64decode(shot["data"]))
        return found, browser.problems(), png
    finally:
        browser.close()


def test_compare_report_loads_cleanly_with_figures(compare_run: CompareRun, tmp_path: Path) -> None:
    found, problems, png = _load(compare_run.out / "report.html", tmp_path)
    assert problems == []
    assert found["cases"] == 1 and found["title"] == "Backend comparison: factory-physics"
    # trajectories: box and door x, y, z; divergence: box and door position and angle, the slider
    assert len(found["plots"]) == 6 + 4 + 1 + 1  # + the event timeline
    assert all(w > 300 and h > 200 for w, h in found["plots"][:-1])
    # start, first event, end for ode and pybullet; start and end for the crash (it died before any event)
    assert len(found["pictures"]) == 3 + 3 + 2 and all(w == 230 and h > 100 for w, h in found["pictures"])
    assert len(found["images"]) == 1
    width, height, complete = found["images"][0]
    assert complete and width == 3 * 240 + 2 * 2 and height > 100  # three panels side by side
    assert found["audios"] == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 50_000


def test_sound_report_plays_each_backends_audio_track(sound_report: SoundReport, tmp_path: Path) -> None:
    found, problems, png = _load(sound_report.out / "report.html", tmp_path)
    assert problems == []
    assert found["audios"] == 2
    # the mix lasts the run (8 s; the thud ends well before)
    assert found["audioDuration"] == pytest.approx(8.0, abs=0.01)
    assert png.stat().st_size > 50_000
