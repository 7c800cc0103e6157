"""Condition triggers, handler options and the assertions on times (becomes, the time of an extremum, a sound's
stop), on the pure-Python backend: these are the runner's semantics (docs/language.md), not an engine's.

The ball is thrown up at v0 = 2 m/s with dt = 0.01 s; the backend integrates like ODE (semi-implicit Euler):
v_n = v0 - n g dt, z_n = z0 + dt (n v0 - g dt n (n + 1) / 2). v_n <= 0 first at n = ceil(v0 / (g dt)) = 21
(v_20 = 0.038, v_21 = -0.0601), so the condition `ball.vel.z <= 0` becomes true in the state at t = 0.21; the
highest state is the last one with v_n > 0, n = 20: z_20 = 1 + 0.01 (40 - 0.0981 * 210) = 1.19399.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest

from runner.language.load import load_scenario
from runner.sim.run import run_loaded
from runner.sim.session import RunResult
from tests.paths import ROOT

V0, G, DT = 2.0, 9.81, 0.01
APEX_STEP = math.ceil(V0 / (G * DT))  # 21
Z_TOP = 1 + DT * ((APEX_STEP - 1) * V0 - G * DT * (APEX_STEP - 1) * APEX_STEP / 2)

HEAD = f"""\
schema_version: 1
scenario: t
world: {{gravity: [0, 0, -{G}], dt: {DT}, duration: 0.5}}
bodies:
  ball: {{sphere: 0.05, mass: 1, pos: [0, 0, 1], vel: [0, 0, {V0}]}}
"""


def run(tmp_path: Path, text: str, variant: str | None = None) -> RunResult:
    path = tmp_path / "t.yaml"
    path.write_text(text)
    return run_loaded(load_scenario(path, variant), "fake", None)


def verdicts(result: RunResult) -> dict[str, tuple[bool, str, str]]:
    return {v.name: (v.passed, v.measured, v.message) for v in result.verdicts}


def test_a_trigger_fires_when_its_condition_becomes_true_and_is_usable_like_any_event(tmp_path: Path) -> None:
    result = run(tmp_path, HEAD + f"""
triggers:
  apex: {{when: ball.vel.z <= 0}}
state: {{seen_at: -1.0}}
on:
  apex: [{{calc: {{seen_at: time}}}}]
assertions:
  - {{name: first, event: apex, first: {APEX_STEP * DT}, tol: 1e-9, count: 1}}
  - {{name: counted, at: end, check: "count('apex') == 1"}}
  - {{name: handled, at: end, value: state.seen_at, near: {APEX_STEP * DT}, tol: 1e-9}}
""")
    assert result.passed, verdicts(result)
    assert [(round(t, 9), name, source) for t, name, source in result.events if name == "apex"] == [
        (APEX_STEP * DT, "apex", "condition")
    ]


def test_a_condition_true_at_the_start_fires_only_after_being_false(tmp_path: Path) -> None:
    # z < 1.1 holds at t=0; it is false from the first state above 1.1 until the ball comes back below it
    result = run(tmp_path, HEAD + """
triggers:
  low: {when: ball.pos.z < 1.1}
""")
    times = [t for t, name, _ in result.events if name == "low"]
    z = [1 + DT * (n * V0 - G * DT * n * (n + 1) / 2) for n in range(51)]
    expected = [n * DT for n in range(1, 51) if z[n] < 1.1 and z[n - 1] >= 1.1 and n < 50]
    assert times == pytest.approx(expected) and len(expected) == 1


@pytest.mark.parametrize("once,count", [(False, 2), (True, 1)])
def test_a_trigger_is_re_armed_when_false_again_unless_once(tmp_path: Path, once: bool, count: int) -> None:
    result = run(tmp_path, HEAD + f"""
triggers:
  window: {{when: time >= 0.1 and time < 0.2 or time >= 0.3, once: {str(once).lower()}}}
assertions:
  - {{name: n, event: window, count: {count}}}
""")
    assert result.passed, verdicts(result)
    assert [round(t, 9) for t, name, _ in result.events if name == "window"] == [0.1, 0.3][:count]


def test_a_trigger_comes_after_the_collision_events_of_the_same_step(tmp_path: Path) -> None:
    # the ball falls from 1 m; the sphere solids (0.05 + 0.05) overlap once z < 0.6, the condition says the same
    result = run(tmp_path, HEAD.replace(f"vel: [0, 0, {V0}]", "vel: [0, 0, 0]") + """
  mark: {box: [0.1, 0.1, 0.1], motion: static, pos: [0, 0, 0.5]}
collisions:
  nodes:
    b: {body: ball, sphere: {radius: 0.05}}
    m: {body: mark, sphere: {radius: 0.05}}
  from: [b]
triggers:
  below: {when: ball.pos.z < 0.6}
""")
    order = [(round(t, 9), name) for t, name, _ in result.events if name in ("b-into-m", "below")]
    assert len(order) == 2 and order[0][0] == order[1][0]
    assert [name for _, name in order] == ["b-into-m", "below"]


def test_handlers_that_run_once_or_not_within_a_minimum_interval(tmp_path: Path) -> None:
    result = run(tmp_path, HEAD + """
state: {a: 0, b: 0, c: 0}
inputs: [{at: 0, event: tick, repeat: {every: 0.1, count: 5}}]
triggers:
  also: {when: time >= 0.05}
on:
  tick: {do: [{calc: {a: state.a + 1}}], once: true}
  also: {do: [{calc: {b: state.b + 1}}], min_interval: 0.25}
assertions:
  - {name: once, at: end, value: state.a, near: 1}
  - {name: every-tick-still-counts, at: end, check: "count('tick') == 5"}
  - {name: interval, at: end, value: state.b, near: 1}
""")
    assert result.passed, verdicts(result)
    result = run(tmp_path, HEAD + """
state: {b: 0}
inputs: [{at: 0, event: tick, repeat: {every: 0.1, count: 5}}]
on:
  tick: {do: [{calc: {b: state.b + 1}}], min_interval: 0.25}
assertions:
  - {name: runs-at-0-0.3, at: end, value: state.b, near: 2}
""")
    assert result.passed, verdicts(result)  # ticks at 0, 0.1, 0.2, 0.3, 0.4: it runs at 0 and 0.3


def test_becomes_gives_the_time_a_condition_first_becomes_true(tmp_path: Path) -> None:
    t = APEX_STEP * DT
    result = run(tmp_path, HEAD + f"""
assertions:
  - {{name: near, becomes: ball.vel.z <= 0, near: {t}, tol: 1e-9}}
  - {{name: within, becomes: ball.vel.z <= 0, within: [0.2, 0.25]}}
  - {{name: too-early, becomes: ball.vel.z <= 0, near: 0.15, tol: 0.01}}
  - {{name: already-true, becomes: ball.pos.z > 0, near: 0}}
""")
    v = {x.name: x for x in result.verdicts}
    assert v["near"].passed and v["within"].passed and v["near"].value == pytest.approx(t)
    assert not v["too-early"].passed and v["too-early"].measured == f"became true at t={t:.6g}"
    assert v["too-early"].expected == "becomes true at 0.15 ± 0.01"
    assert not v["already-true"].passed and v["already-true"].measured == "true from the start and never false"


def test_the_time_and_value_of_an_extremum(tmp_path: Path) -> None:
    top = (APEX_STEP - 1) * DT
    result = run(tmp_path, HEAD + f"""
assertions:
  - {{name: apex, max: ball.pos.z, during: [0, 0.4], near: {Z_TOP!r}, tol: 1e-9, time: {top}, time_tol: 1e-9}}
  - {{name: apex-window, max: ball.pos.z, time_within: [0.15, 0.25]}}
  - {{name: apex-late, max: ball.pos.z, time: 0.3, time_tol: 0.01}}
""")
    v = {x.name: x for x in result.verdicts}
    assert v["apex"].passed and v["apex"].time == pytest.approx(top) and v["apex"].value == pytest.approx(Z_TOP)
    assert v["apex-window"].passed
    assert not v["apex-late"].passed and v["apex-late"].message == f"reached at t={top:.6g}"


def test_a_sounds_stop_time_and_duration(tmp_path: Path) -> None:
    shutil.copytree(ROOT / "scenarios" / "sounds", tmp_path / "sounds")
    # thud.wav lasts 7717 samples at 22050 Hz = 0.349977 s; `stop_sound` at 0.1 cuts the second play short
    length = 7717 / 22050
    result = run(tmp_path, HEAD + f"""
sounds: {{thud: sounds/thud.wav}}
inputs: [{{at: 0, event: play}}, {{at: 0.05, event: stop}}, {{at: 0.1, event: play}}]
on:
  play: [{{play_sound: thud}}]
  stop: [{{stop_sound: thud}}]
assertions:
  - {{name: cut, sound: thud, stopped_at: 0.05, tol: 1e-9}}
  - {{name: natural-end, sound: thud, stopped_at: {0.1 + length!r}, tol: 1e-9}}
  - {{name: durations, sound: thud, duration: {length!r}, tol: 1e-9}}
""")
    v = {x.name: x for x in result.verdicts}
    assert v["cut"].passed and v["natural-end"].passed
    assert not v["durations"].passed  # the first play lasted 0.05 s
    assert v["durations"].message == f"played for [0.05, {length:.6g}] s"


def test_a_failing_condition_shows_the_values_it_read_and_the_member_of_a_group(tmp_path: Path) -> None:
    result = run(tmp_path, HEAD + """
  crate: {box: [0.1, 0.1, 0.1], mass: 1, pos: [1, 0, 1], array: {count: 3, spacing: [0, 0, 0.3]}}
assertions:
  - {name: low, at: 0.1, check: ball.pos.z < 1}
  - {name: under, always: max(crate.pos.z) < 1.5}
""")
    v = {x.name: x for x in result.verdicts}
    assert v["low"].message.startswith("false at t=0.1000: ball.pos.z = 1.1") and not v["low"].passed
    assert v["under"].message == "false at t=0.0000: crate.pos.z = [1, 1.3, 1.6], max(crate.pos.z) = 1.6 (crate_2)"
