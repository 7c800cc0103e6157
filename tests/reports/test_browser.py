"""The HTML report in a real headless Chromium (Debian's `chromium`), loaded from a file:// URL.

Checks what a reader relies on: no console error or warning, no uncaught exception, no failed load and
no request other than file: and data:; the headline's words are report.json's; every body of the scene
shows in every picture (its colour, as lit, near where the camera projects its centre; a plane's colour
somewhere); the 3D replay's slider and play button move the bodies, and it widens to the page's width;
the charts draw and answer a hover with the values under the pointer; audio tracks decode to the run's
length. About 20 s. Skipped only when no Chromium is installed (CI installs it: apt-get install chromium);
with SCENARIO_REQUIRE_BROWSER=1 (set by .ci/run) a missing browser fails instead.
"""

from __future__ import annotations

import base64
import json
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from backends.registry import is_installed
from reports.trace_reader import read_trace

from .cdp import Browser, find_chromium
from .conftest import CompareRun, SoundReport

CHROMIUM = find_chromium()
REQUIRED = os.environ.get("SCENARIO_REQUIRE_BROWSER") == "1"
pytestmark = pytest.mark.skipif(
    CHROMIUM is None and not REQUIRED, reason="no Chromium on this machine (apt-get install chromium)"
)
HERE = Path(__file__).parent

#: the colour test of test_scene3d, in the page: k * rgb within 14 levels for some k in [0.3, 1.1] (``var``: the
#: page keeps them from one evaluation to the next)
LIT_LIKE = """
var litLike = (p, rgb) => {
  const c = rgb.map(v => v);
  const k = (p[0] * c[0] + p[1] * c[1] + p[2] * c[2]) / (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  return k >= 0.3 && k <= 1.1 && Math.max(...[0, 1, 2].map(i => Math.abs(p[i] - k * c[i]))) <= 14;
};
var pixels = (source, sx, sy, w, h) => {
  const canvas = document.createElement('canvas');
  canvas.width = w; canvas.height = h;
  const ctx = canvas.getContext('2d');
  ctx.drawImage(source, sx, sy, w, h, 0, 0, w, h);
  return ctx.getImageData(0, 0, w, h).data;
};
var foundNear = (data, w, h, px, rgb, r = 3) => {
  for (let y = Math.round(px[1]) - r; y <= Math.round(px[1]) + r; y++)
    for (let x = Math.round(px[0]) - r; x <= Math.round(px[0]) + r; x++) {
      if (x < 0 || y < 0 || x >= w || y >= h) continue;
      const i = 4 * (y * w + x);
      if (litLike([data[i], data[i + 1], data[i + 2]], rgb)) return true;
    }
  return false;
};
var foundIn = (data, w, h, box, rgb) => {
  for (let y = Math.floor(box[1]); y <= Math.ceil(box[3]); y++)
    for (let x = Math.floor(box[0]); x <= Math.ceil(box[2]); x++) {
      if (x < 0 || y < 0 || x >= w || y >= h) continue;
      const i = 4 * (y * w + x);
      if (litLike([data[i], data[i + 1], data[i + 2]], rgb)) return true;
    }
  return false;
};
var share = (data, rgb) => {
  let n = 0;
  for (let i = 0; i < data.length; i += 4) if (litLike([data[i], data[i + 1], data[i + 2]], rgb)) n++;
  return n / (data.length / 4);
};
"""

PICTURES = LIT_LIKE + """
(async () => {
  const out = [];
  for (const img of document.querySelectorAll('img.picture')) {
    await img.decode();
    const data = pixels(img, 0, 0, img.naturalWidth, img.naturalHeight);
    const bodies = JSON.parse(img.dataset.bodies);
    for (const [name, b] of Object.entries(bodies)) {
      // a body: its colour near its centre, or (partly hidden behind another) inside its projected outline
      const [w, h] = [img.naturalWidth, img.naturalHeight];
      const near = b.px !== null && foundNear(data, w, h, b.px, b.rgb);
      const seen = b.plane ? share(data, b.rgb) > 0.01 : near || (b.box !== null && foundIn(data, w, h, b.box, b.rgb));
      out.push([img.closest('section').id, img.dataset.t, img.dataset.backends, name, b.plane, b.px, near, seen]);
    }
  }
  return out;
})()"""


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Browser]:
    if CHROMIUM is None:
        pytest.fail("SCENARIO_REQUIRE_BROWSER=1 but no Chromium is installed (apt-get install chromium)")
    b = Browser(CHROMIUM, tmp_path_factory.mktemp("profile"))
    for domain in ("Page", "Runtime", "Log", "Network"):
        b.call(f"{domain}.enable")
    b.call("Emulation.setDeviceMetricsOverride", width=1400, height=1000, deviceScaleFactor=1, mobile=False)
    try:
        yield b
    finally:
        b.close()


def _open(browser: Browser, page: Path) -> None:
    browser.events.clear()
    browser.call("Page.navigate", url=page.resolve().as_uri())
    browser.wait_for("Page.loadEventFired")


def _until(browser: Browser, condition: str, timeout: float = 30.0) -> Any:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = browser.evaluate(condition)
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {condition}")


def _screenshot(browser: Browser, path: Path) -> Path:
    shot = browser.call("Page.captureScreenshot", format="png")
    path.write_bytes(base64.b64decode(shot["data"]))
    return path


def test_the_headline_says_what_report_json_says(browser: Browser, compare_run: CompareRun, tmp_path: Path) -> None:
    _open(browser, compare_run.out / "report.html")
    doc = compare_run.doc
    found = browser.evaluate("""(() => ({
      badge: document.querySelector('p.verdict .badge').textContent,
      text: document.getElementById('headline').textContent,
      cases: [...document.querySelectorAll('section.case')].map(s => [s.querySelector('h2 .badge').textContent,
        s.querySelector('h2 .headline').textContent]),
      title: document.title }))()""")
    assert found["title"] == "Backend comparison: factory-physics"
    assert (found["badge"], found["text"]) == (doc["headline"]["badge"], doc["headline"]["text"])
    assert found["cases"] == [[c["headline"]["badge"], c["headline"]["text"]] for c in doc["cases"]]
    assert doc["headline"]["text"].startswith("1 run crashed (signal 11)")  # the crash backend of the shared run
    assert _screenshot(browser, tmp_path / "first-screen.png").stat().st_size > 20_000
    assert browser.problems() == []


@pytest.mark.slow
@pytest.mark.parametrize("which", ["demo_compare", "kuka_compare"])
def test_the_judgement_among_engines_shows_as_report_json_says(browser: Browser, which: str,
                                                               request: pytest.FixtureRequest) -> None:
    """`make demo`'s comparison and the robot arm's (the four engines; about 15 s and 12 s to run): the page's
    headline is report.json's, word for word, at the top and in every case, and the engines named as departing
    are listed with the documented cause the data show."""
    run: CompareRun = request.getfixturevalue(which)
    assert run.done.returncode == 0, run.done.stdout + run.done.stderr
    _open(browser, run.out / "report.html")
    doc = run.doc
    found = browser.evaluate("""(() => ({
      badge: document.querySelector('p.verdict .badge').textContent,
      text: document.getElementById('headline').textContent,
      departures: [...document.querySelectorAll('body > ul.agreement li.departure')].map(li => [li.dataset.backend,
        li.querySelector('code') ? li.querySelector('code').textContent : null]),
      cases: [...document.querySelectorAll('section.case')].map(s => [s.querySelector('h2 .badge').textContent,
        s.querySelector('h2 .headline').textContent]) }))()""")
    h = doc["headline"]
    assert (found["badge"], found["text"]) == (h["badge"], h["text"]) and h["badge"] == "PASS"
    assert found["cases"] == [[c["headline"]["badge"], c["headline"]["text"]] for c in doc["cases"]]
    assert found["departures"] == [[d["backend"], d["cause"]["link"] if d.get("cause") else None]
                                   for d in h["agreement"]["departures"]]  # fmt: skip
    if which == "demo_compare":  # ODE departs, and its soft slider's sag is why
        assert found["departures"] == [["ode", "docs/backends/ode.md#deviations-from-textbook-physics-odes-own-kept"]]
    else:  # ODE departs (its servo), or, once its servo matches the others', the four agree
        assert found["departures"] in ([["ode", None]], [])
        assert ("4 engines agree" in h["text"]) == (not found["departures"])
    assert browser.problems() == []


def test_every_body_shows_in_every_picture(browser: Browser, compare_run: CompareRun) -> None:
    _open(browser, compare_run.out / "report.html")
    found = browser.evaluate(PICTURES)
    bodies = {row[3] for row in found}
    assert bodies == {"box", "door", "basement"}
    moments = [m["t"] for m in compare_run.doc["cases"][0]["key_moments"]]
    assert {float(row[1]) for row in found} == set(moments)
    missing = [row for row in found if not row[-1]]
    # the crash backend has no contacts: its box falls through the door and its last recorded step (t = 1 s) has
    # it wholly under the door's top face, inside its outline: hidden from a camera above, as it should be
    trace = read_trace(compare_run.traces / "factory-physics__door-stays-closed__crash.mcap.partial", recover=True)
    box, door = trace.bodies["box"].pos[-1], trace.bodies["door"].pos[-1]
    under = box[2] + 0.15 < door[2] + 0.05 and abs(box[0] - door[0]) < 1 - 0.15 and abs(box[1] - door[1]) < 1 - 0.15
    hidden = [row for row in missing if row[2] == "crash" and row[3] == "box" and float(row[1]) >= 1.0 and under]
    assert [row for row in missing if row not in hidden] == [], f"bodies not drawn where they are: {missing}"
    assert len(found) - len(hidden) >= 3 * len(moments)
    assert browser.problems() == []


def test_the_replay_slider_and_play_button_move_the_bodies(browser: Browser, compare_run: CompareRun) -> None:
    _open(browser, compare_run.out / "report.html")
    data = browser.evaluate("""(() => { const d = document.querySelector('#case-0 details.replay'); d.open = true;
      d.scrollIntoView(); return JSON.parse(d.querySelector('script.replay-data').textContent); })()""")
    _until(browser, "document.querySelector('#case-0 div.replay').dataset.loaded === '1'")
    box = data["bodies"].index("box")
    row = data["backends"].index("ode")
    # a frame in flight and one after landing: the box's centre moves by many pixels between them
    early = 3
    path = [c[box] for c in data["centres"]["ode"]]
    late = next(k for k, c in enumerate(path) if c[1] - path[early][1] > 30)
    checks = []
    for frame in (early, late):
        checks.append(browser.evaluate(LIT_LIKE + f"""(async () => {{
          const el = document.querySelector('#case-0 div.replay');
          const slider = el.querySelector('input[type=range]');
          slider.value = '{frame}'; slider.dispatchEvent(new Event('input'));
          await new Promise(done => setTimeout(done, 100));
          const d = {json.dumps({k: data[k] for k in ("w", "h", "gap", "centres", "colours")})};
          const canvas = el.querySelector('canvas');
          const x0 = {row} * (d.w + d.gap);
          const panel = pixels(canvas, x0, 0, d.w, d.h);
          const here = d.centres.ode[{frame}][{box}], there = d.centres.ode[{early + late - frame}][{box}];
          return [el.dataset.frame, el.querySelector('.clock').textContent, foundNear(panel, d.w, d.h, here,
            d.colours.box), foundNear(panel, d.w, d.h, there, d.colours.box)];
        }})()"""))
    for (frame_text, clock, here, there), frame in zip(checks, (early, late), strict=True):
        assert frame_text == str(frame) and clock == f"t = {data['times'][frame]:.2f} s"
        assert here and not there  # the box is where that frame has it, and no longer (or not yet) elsewhere
    browser.evaluate("document.querySelector('#case-0 div.replay button.play').click()")
    _until(browser, f"Number(document.querySelector('#case-0 div.replay').dataset.frame) > {late}")
    # full width: the frames scaled to the replay's whole width (the page's), and back to their own size
    sizes = browser.evaluate("""(() => { const el = document.querySelector('#case-0 div.replay');
      const canvas = el.querySelector('canvas'), button = el.querySelector('button.wide');
      const shown = () => canvas.getBoundingClientRect().width;
      const before = shown(); button.click(); const wide = shown(), label = button.textContent;
      button.click(); return [before, wide, el.clientWidth, canvas.width, label, shown()]; })()""")
    before, wide, container, own, label, after = sizes
    assert before == after == min(own, container)
    assert abs(wide - container) <= 1 and label == "⤡ actual size"
    assert browser.problems() == []


def test_charts_draw_and_answer_a_hover(browser: Browser, compare_run: CompareRun) -> None:
    _open(browser, compare_run.out / "report.html")
    count = browser.evaluate("""(() => { document.querySelectorAll('#case-0 details').forEach(d => d.open = true);
      return document.querySelectorAll('#case-0 div.chart').length; })()""")
    case = compare_run.doc["cases"][0]
    assert count >= len(case["quantities"]) + 6 + 1  # deviations, the box's and door's x y z, the slider, events
    browser.evaluate("document.querySelector('#case-0 div.chart').scrollIntoView()")
    _until(browser, "[...document.querySelectorAll('#case-0 div.chart')].slice(0, 2).every(e => e.dataset.ready)")
    first = browser.evaluate("""(() => { const el = document.querySelector('#case-0 div.chart');
      const texts = [...el.querySelectorAll('text')].map(t => t.textContent);
      const pts = el.querySelectorAll('g.layer_2_marks path'); const p = pts[Math.floor(pts.length / 2)];
      const r = p.getBoundingClientRect();
      return {texts, x: r.left + r.width / 2, y: r.top + r.height / 2}; })()""")
    assert "t (s)" in first["texts"] and "deviation (m)" in first["texts"]
    assert any(t.startswith("threshold 0.01 m") for t in first["texts"])
    browser.call("Input.dispatchMouseEvent", type="mouseMoved", x=first["x"] - 1, y=first["y"])
    browser.call("Input.dispatchMouseEvent", type="mouseMoved", x=first["x"], y=first["y"])
    tip = _until(browser, """(() => { const t = document.getElementById('vg-tooltip-element');
      return t && t.classList.contains('visible') ? t.textContent : null; })()""")
    assert "backend" in tip and "t (s)" in tip and "deviation (m)" in tip
    assert any(b in tip for b in ("ode", "crash", "pybullet"))
    # a click on a legend entry keeps that backend and fades the others
    label = browser.evaluate("""(() => { const el = document.querySelector('#case-0 div.chart');
      const t = [...el.querySelectorAll('g.role-legend-label text')].find(t => t.textContent === 'pybullet');
      const r = t.getBoundingClientRect(); return {x: r.left + r.width / 2, y: r.top + r.height / 2}; })()""")
    for kind in ("mousePressed", "mouseReleased"):
        browser.call("Input.dispatchMouseEvent", type=kind, x=label["x"], y=label["y"], button="left", clickCount=1)
    faded = _until(browser, """(() => { const el = document.querySelector('#case-0 div.chart');
      const o = [...el.querySelectorAll('g.mark-line path')].map(p => p.getAttribute('opacity'));
      return o.includes('0.12') ? o : null; })()""")
    assert faded.count("1") == 1  # pybullet's line stays, the other backends' fade
    assert browser.problems() == []


@pytest.fixture(scope="module")
def ramp_report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """ball_on_ramp.yaml on ode and pybullet, in process (about 2 s), and its report."""
    from reports.build import write_report
    from runner.language.load import load_scenario
    from runner.sim.run import run_loaded

    for name in ("ode", "pybullet"):
        if not is_installed(name):
            pytest.skip(f"engine not installed: {name}")
    out = tmp_path_factory.mktemp("ramp")
    case = load_scenario(HERE / "scenarios" / "ball_on_ramp.yaml", "rolls")
    for backend in ("ode", "pybullet"):
        run_loaded(case, backend, out / "traces")
    write_report([out / "traces"], out)
    return out / "report.html"


def test_a_ball_on_a_ramp_shows_in_every_picture(browser: Browser, ramp_report: Path) -> None:
    _open(browser, ramp_report)
    found = browser.evaluate(PICTURES)
    assert {row[3] for row in found} == {"floor", "ramp", "ball"}
    assert len({row[1] for row in found}) >= 2  # at least the start and the end
    missing = [row for row in found if not row[-1]]
    assert not missing, f"bodies not drawn where they are: {missing}"
    assert browser.problems() == []


def test_sound_report_plays_each_backends_audio_track(browser: Browser, sound_report: SoundReport) -> None:
    _open(browser, sound_report.out / "report.html")
    durations = browser.evaluate("""(async () => Promise.all([...document.querySelectorAll('audio')].map(audio =>
      new Promise(done => { const a = new Audio(); a.addEventListener('loadedmetadata', () => done(a.duration));
        a.addEventListener('error', () => done(-1)); a.src = audio.src; }))))()""")
    # the mix lasts the run (8 s; the thud ends well before)
    assert durations == [pytest.approx(8.0, abs=0.01)] * 2
    assert browser.problems() == []
