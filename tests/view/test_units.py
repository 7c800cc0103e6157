"""The viewer's plain parts: Panda3D event names, the viewer's keys, the heads-up lines, the orbit
camera, script files. No window, no engine."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from reports.scene3d.framing import LAB_CAMERA, CameraSpec
from runner.errors import UsageError
from runner.language import model_assertions as A
from runner.sim.assertions import Verdict
from runner.view.camera import MAX_DISTANCE, MIN_DISTANCE, Orbit
from runner.view.hud import Hud
from runner.view.keys import RESERVED, button_event, named_events, reserved_action
from runner.view.script import load_script


def test_button_events_get_panda3d_names() -> None:
    # ButtonThrower: presses carry the modifier prefix, repeats add -repeat, releases are the bare button + -up
    assert button_event("down", "space") == "space"
    assert button_event("down", "shift-space") == "shift-space"
    assert button_event("repeat", "space") == "space-repeat"
    assert button_event("up", "space") == "space-up"
    assert button_event("down", "mouse1") == "mouse1"


def test_the_viewers_keys_never_reach_the_scenario() -> None:
    assert reserved_action("f3") == "pause" and reserved_action("escape") == "close"
    assert reserved_action("f3-up") == "" and reserved_action("f3-repeat") == ""
    assert reserved_action("space") is None and reserved_action("shift-f3") is None
    assert all(name.startswith("f") or name == "escape" for name in RESERVED)


def test_the_events_a_scenario_names_are_its_handlers_and_event_assertions() -> None:
    a = A.EventAssertion(name="n", event="box-into-door", before="space-up")
    assert named_events(["space", "mouse1"], [a]) == {"space", "mouse1", "box-into-door", "space-up"}


def test_the_lab_camera_is_the_seeds() -> None:
    assert LAB_CAMERA.pos == (1.0, -8.0, 5.0) and LAB_CAMERA.pitch == -25.0 and LAB_CAMERA.heading == 0.0
    # 4:3 with 40 degrees across: tan(v/2) = tan(20 deg) * 3/4
    assert LAB_CAMERA.fov[1] == pytest.approx(math.degrees(2 * math.atan(math.tan(math.radians(20)) * 0.75)))


def test_the_orbit_starts_where_the_camera_is_and_keeps_its_pivot() -> None:
    orbit = Orbit.looking_from(LAB_CAMERA, [(1, 0, 2), (1, 0, 0)])
    assert np.allclose(orbit.spec(LAB_CAMERA.fov).pos, LAB_CAMERA.pos)
    _, forward, _ = LAB_CAMERA.axes()
    # the pivot is the point of the line of sight nearest the bodies' centre (1, 0, 1)
    assert np.dot(np.subtract((1, 0, 1), orbit.pivot), forward) == pytest.approx(0, abs=1e-12)
    for dx, dy in ((0.3, 0.0), (-0.2, 0.4), (0.0, -5.0)):
        orbit.drag(dx, dy)
        spec = orbit.spec(LAB_CAMERA.fov)
        assert np.linalg.norm(np.subtract(spec.pos, orbit.pivot)) == pytest.approx(orbit.distance)
        assert -89.0 <= spec.pitch <= 89.0
        _, f, _ = spec.axes()  # still looking at the pivot
        assert np.allclose(np.asarray(spec.pos) + f * orbit.distance, orbit.pivot)
    before = orbit.distance
    orbit.zoom(2)
    assert orbit.distance < before
    orbit.zoom(-400)
    assert orbit.distance == MAX_DISTANCE
    orbit.zoom(400)
    assert orbit.distance == MIN_DISTANCE


def test_with_aspect_keeps_the_horizontal_field_of_view() -> None:
    wide = CameraSpec((0, 0, 0), fov=(60.0, 10.0)).with_aspect(2.0)
    assert wide.fov[0] == 60.0
    assert math.tan(math.radians(wide.fov[1] / 2)) == pytest.approx(math.tan(math.radians(30)) / 2)


def test_the_heads_up_lines_say_time_events_sounds_and_verdicts() -> None:
    hud = Hud(title="factory-physics", end_time=6.0, time=1.25, recording="played", played=2)
    for k in range(7):
        hud.event(0.04 * k, f"e{k}")
    hud.sounds = {"thud": 1.0}
    hud.verdicts = [Verdict("kick", "value", True, "1", "1"), Verdict("rest", "value", False, "0", "1")]
    hud.pending = 3
    lines = hud.lines()
    assert lines[0].startswith("t   1.25 / 6.00 s  x1  running")
    assert "e0" not in lines[1] and "e2" in lines[1] and "e6" in lines[1]  # the last five
    assert lines[2] == "sounds: thud"
    assert lines[3].startswith("verdicts: 1 pass, 1 FAIL, 3 to come") and "FAIL rest" in lines[3]
    assert any("'played': 2 input(s)" in line for line in lines)
    hud.speed = 0.25
    assert "x1/4" in hud.lines()[0]


def test_a_script_is_read_and_each_wrong_entry_named(tmp_path: Path) -> None:
    good = tmp_path / "s.yaml"
    good.write_text("- {at: 1.2, event: space}\n- {after: 0.5, screenshot: a.png}\n- {at: 3, close: true}\n")
    entries = load_script(good)
    assert [(e.at, e.after, e.event, e.close) for e in entries] == [
        (1.2, None, "space", False), (None, 0.5, "", False), (3.0, None, "", True)]  # fmt: skip
    assert entries[1].screenshot == Path("a.png")
    for text, words in [
        ("{at: 1}", "expected a list"),
        ("- {at: 1, after: 2, event: x}", "exactly one of `at`"),
        ("- {at: -1, event: x}", "entry 1: `at` must be a number"),
        ("- {at: 1, event: x, close: true}", "exactly one of `event`"),
        ("- {at: 1, kick: x}", "unknown key `kick`"),
        ("- {at: 1, close: false}", "`close` must be true"),
        ("- [at, 1", "not YAML"),
    ]:
        bad = tmp_path / "bad.yaml"
        bad.write_text(text)
        with pytest.raises(UsageError, match=words):
            load_script(bad)
