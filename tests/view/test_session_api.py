"""Session.advance() and Session.inject(): the additive API a live run drives the step loop with.

An event injected at a step boundary is delivered exactly as a timed input due there: the lab's physics
scene with its two timed inputs (space at 1.52 s, mouse1 at 7.0 s) and the same scene with no timed
input but the two events injected at steps 38 and 175 give the same trace, step for step (PyBullet);
and the window hears, through the tap, every scene update, event and sound the trace records.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from reports.scene3d.model import EntityVisual, scene_model
from reports.trace_reader import read_trace
from runner.compile.program import build_program
from runner.language.load import load_scenario, parse_overrides
from runner.sim.run import run_loaded, solid_visuals
from runner.sim.session import RunResult, Session
from runner.view.tap import TraceTap, scene_entities
from tests.view.conftest import ROOT, assert_same_run

FACTORY = ROOT / "scenarios" / "factory_physics.yaml"
VARIANT = "door-moves-away-box-falls"
BACKEND = "pybullet"


def _injecting(plan: dict[int, list[str]]):  # noqa: ANN202
    def drive(session: Session) -> RunResult:
        steps = session.advance()
        assert next(steps) == 0.0  # before the first step
        k = 0
        while True:
            for event in plan.get(k, []):
                session.inject(event)
            try:
                t = next(steps)
            except StopIteration as done:
                return done.value
            k += 1
            assert t == k * session.dt

    return drive


def test_an_injected_event_is_a_timed_input_due_at_that_step(tmp_path: Path) -> None:
    timed = run_loaded(load_scenario(FACTORY, VARIANT), BACKEND, tmp_path / "timed")
    bare = load_scenario(FACTORY, VARIANT, parse_overrides([f"variants.{VARIANT}.inputs=[]"]))
    assert build_program(bare).inputs == []
    injected = run_loaded(bare, BACKEND, tmp_path / "injected", drive=_injecting({38: ["space"], 175: ["mouse1"]}))
    a, b = read_trace(timed.trace), read_trace(injected.trace)
    assert [(e.t, e.name) for e in a.events if e.source == "input"] == [(38 * 0.04, "space"), (175 * 0.04, "mouse1")]
    assert_same_run(a, b)
    assert timed.status == injected.status == "passed"


def test_a_drained_advance_is_run(tmp_path: Path) -> None:
    loaded = load_scenario(FACTORY, VARIANT)
    a = run_loaded(loaded, BACKEND, tmp_path / "run")
    b = run_loaded(loaded, BACKEND, tmp_path / "advance", drive=_injecting({}))
    assert (tmp_path / "run" / Path(a.trace or "").name).read_bytes() == Path(b.trace or "").read_bytes()


class _Heard:
    def __init__(self) -> None:
        self.scene: list[tuple[float, dict[str, EntityVisual | None]]] = []
        self.events: list[tuple[float, str, str]] = []
        self.sounds: list[tuple[float, str, str]] = []
        self.logs: list[tuple[float, str]] = []

    def on_scene(self, t: float, entities: Sequence[EntityVisual]) -> None:
        self.scene.append((t, {e.id: e for e in entities}))

    def on_event(self, t: float, name: str, source: str) -> None:
        self.events.append((t, name, source))

    def on_log(self, t: float, level: str, message: str, name: str) -> None:
        self.logs.append((t, message))

    def on_sound(self, t: float, name: str, action: str, offset: float, volume: float) -> None:
        self.sounds.append((t, name, action))


def _tapped(heard: _Heard):  # noqa: ANN202
    def drive(session: Session) -> RunResult:
        session.trace = TraceTap(session.trace, heard)
        return session.run()

    return drive


def test_the_window_hears_the_scene_the_trace_records(tmp_path: Path) -> None:
    """A box that grows (scale intervals) and has a collision solid: every scene update, as read back."""
    loaded = load_scenario(ROOT / "tests" / "reports" / "scenarios" / "growing_box.yaml")
    heard = _Heard()
    result = run_loaded(loaded, "fake", tmp_path, drive=_tapped(heard))
    program = build_program(loaded)
    first = scene_entities(program.world.bodies, solid_visuals(program))  # what the window starts from
    assert len(heard.scene) >= 2  # the box's scale changed during the run
    live = [(0.0, {e.id: e for e in first}), *heard.scene]
    recorded = scene_model(read_trace(result.trace)).updates
    # the same entities at the same times (the trace keeps times to the nanosecond)
    assert [(round(t * 1e9), u) for t, u in live] == [(round(t * 1e9), u) for t, u in recorded]


def test_the_window_hears_the_events_and_sounds_the_trace_records(tmp_path: Path) -> None:
    loaded = load_scenario(ROOT / "scenarios" / "factory_intervals.yaml", "door-closed")
    heard = _Heard()
    result = run_loaded(loaded, BACKEND, tmp_path, drive=_tapped(heard))
    trace = read_trace(result.trace)
    assert heard.events == [(e.t, e.name, e.source) for e in trace.events]
    # the trace keeps times to the nanosecond (a sound ends at its length after its start)
    ns = [(round(s.t * 1e9), s.name, s.action) for s in trace.sounds]
    assert [(round(t * 1e9), n, a) for t, n, a in heard.sounds] == ns
    assert ("thud" in {s[1] for s in heard.sounds}) and any("hit the door" in m for _, m in heard.logs)
