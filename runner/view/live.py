"""A live run in the window: the session's own step loop, paced to the wall clock, fed by keys and clicks.

:meth:`LiveRun.drive` is handed to :func:`runner.sim.run.run_loaded` in place of ``Session.run``, so the
live run builds, records and finishes its trace exactly as ``scenario run`` does; it advances the
session one step at a time (:meth:`runner.sim.session.Session.advance`) when the wall clock says so
(``speed`` simulated seconds per second; paused and single-stepped by keys), and gives it the window's
input events with :meth:`Session.inject`, which delivers them at the next step boundary exactly as a
timed input due there. Each one is remembered as (step, event) for ``--record``. The trace writer is
wrapped by :class:`runner.view.tap.TraceTap`, so the window shows the scene, events and sounds the trace
records as they are recorded. When the window is closed before the end, the rest of the run goes on
without it (no pacing, no inputs), so the trace and the verdicts always cover the whole scenario.
"""

from __future__ import annotations

import math
import time
from collections.abc import Generator, Sequence
from pathlib import Path
from typing import Any

from reports.scene3d.model import EntityVisual, SceneModel
from runner import interrupts
from runner.sim.session import RunResult, Session
from runner.view.audio import SoundPlayer
from runner.view.hud import Hud
from runner.view.record import Played
from runner.view.script import ScriptEntry
from runner.view.window import ViewWindow

__all__ = ["LiveRun", "MAX_LAG", "MAX_SPEED", "MIN_SPEED"]

MAX_LAG = 0.25  # simulated seconds behind the wall clock before the pacing gives up catching up
FRAME = 1 / 60  # seconds: the window is redrawn at most this often
MIN_SPEED, MAX_SPEED = 1 / 16, 4.0


class LiveRun:
    """Drives one session in ``window`` (see the module docstring)."""

    def __init__(self, window: ViewWindow, scene_model: SceneModel, hud: Hud, *, events: frozenset[str],
                 dt: float, steps: int, speed: float = 1.0, paused: bool = False,
                 script: Sequence[ScriptEntry] = (), sounds: dict[str, Path] | None = None) -> None:  # fmt: skip
        self.window = window
        self.model = scene_model
        self.hud = hud
        self.events = events
        self.dt = dt
        self.steps = steps
        self.speed = min(MAX_SPEED, max(MIN_SPEED, speed))
        self.hud.speed = self.speed
        self.paused = paused
        self.hud.mode = "paused" if paused else "running"
        self.script = list(script)
        self._scripted = bool(script)
        self._over = False  # the run has ended: every simulated-time script entry is due
        self.played: list[Played] = []
        self.k = 0  # steps done: the next input is delivered at the start of step k, at k * dt
        self.t = 0.0
        self.session: Session | None = None
        self.result: RunResult | None = None
        self._step_once = False
        self._anchor = (time.perf_counter(), 0.0)
        self._opened = time.perf_counter()
        self.sounds = SoundPlayer(window.base, sounds or {})
        window.on_input = self.on_input
        window.on_action = self.on_action
        self._shown: list[Any] = []

    # ---- the window's inputs ----------------------------------------------------------------------
    def on_input(self, name: str) -> None:
        session = self.session
        if session is None or self.result is not None or self.window.closed or self.k >= self.steps:
            return
        if name in self.events:
            session.inject(name)
            self.played.append(Played(self.k, name))
            self.hud.queued.append(name)
            self.hud.played = len(self.played)
        elif not name.endswith(("-up", "-repeat")) and "mouse" not in name and not name.startswith("wheel"):
            self.hud.note = f"'{name}' is not an event this scenario names: not delivered"

    def on_action(self, action: str) -> None:
        if action == "pause":
            self.paused = not self.paused
            self._anchor = (time.perf_counter(), self.t)
        elif action == "step":
            self._step_once = self.paused
        elif action in ("slower", "faster"):
            self.speed = min(MAX_SPEED, max(MIN_SPEED, self.speed * (0.5 if action == "slower" else 2.0)))
            self._anchor = (time.perf_counter(), self.t)
            self.hud.speed = self.speed
        elif action == "closed":
            self.sounds.stop_all()
        if self.result is None:
            self.hud.mode = "paused" if self.paused else "running"

    # ---- what the trace records (runner.view.tap.TapListener) ---------------------------------------
    def on_scene(self, t: float, entities: Sequence[EntityVisual]) -> None:
        self.model.add_update(t, entities)

    def on_event(self, t: float, name: str, source: str) -> None:
        self.hud.event(t, name)

    def on_log(self, t: float, level: str, message: str, name: str) -> None:
        if name == "handler":
            self.hud.note = f"{t:.2f} log: {message}"

    def on_sound(self, t: float, name: str, action: str, offset: float, volume: float) -> None:
        if action == "start":
            loop = self.session is not None and self.session.playing_sounds.get(name) == math.inf
            self.hud.sounds[name] = t
            if not self.window.closed:
                self.sounds.play(name, offset, volume, loop)
        else:
            self.hud.sounds.pop(name, None)
            self.sounds.stop(name)

    # ---- the loop ---------------------------------------------------------------------------------
    def _show(self) -> None:
        session = self.session
        if session is None or self.window.closed:
            return
        states = session.snapshot.bodies
        for scene in self.window.scenes:
            scene.show(self.t)
            for i, name in enumerate(session.names):
                scene.set_pose(name, states.pos[i], states.quat[i])
        decided = [c.done for c in session.tracker.checks if c.done is not None]
        for v in decided:
            if all(v is not w for w in self._shown):
                self._shown.append(v)
        self.hud.verdicts = list(self._shown)
        self.hud.pending = len(session.tracker.checks) - len(decided)
        self.hud.time = self.t

    def _due_script(self) -> list[ScriptEntry]:
        from runner.view.record import due_step

        now = time.perf_counter() - self._opened
        due = [e for e in self.script if (e.at is not None and (self._over or due_step(e.at, self.dt) <= self.k))
               or (e.after is not None and e.after <= now)]  # fmt: skip
        for e in due:
            self.script.remove(e)
        return due

    def _script_waits_here(self) -> bool:
        from runner.view.record import due_step

        return any(e.at is not None and due_step(e.at, self.dt) <= self.k for e in self.script)

    def _run_script(self) -> None:
        for entry in self._due_script():
            if entry.event:
                self.window.button(entry.event)
            elif entry.screenshot is not None:
                self._show()
                self.window.frame()
                self.window.screenshot(entry.screenshot)
            elif entry.close:
                self.window.close()

    def _one(self, steps: Generator[float, None, RunResult]) -> bool:
        """One step; False when the run is over."""
        try:
            self.t = next(steps)
        except StopIteration as done:
            self.result = done.value
            return False
        self.k += 1
        self.hud.queued.clear()
        return True

    def _due_steps(self) -> int:
        if self.paused:
            return 1 if self._step_once else 0
        wall0, sim0 = self._anchor
        now = time.perf_counter()
        target = sim0 + (now - wall0) * self.speed
        if target - self.t > MAX_LAG:  # drawing is slower than the run: go on from here, do not race
            self._anchor = (now - self.dt / self.speed, self.t)
            return 1
        return max(0, int(math.floor((target - self.t) / self.dt + 1e-9)))

    def drive(self, session: Session) -> RunResult:
        """Run ``session`` live (the ``drive`` of runner.sim.run.run_loaded); the run's result."""
        from runner.view.tap import TraceTap

        self.session = session
        if session.trace is not None:
            session.trace = TraceTap(session.trace, self)
        steps = session.advance()
        self.t = next(steps)
        self._anchor = (time.perf_counter(), self.t)
        self._show()
        while not self.window.closed:
            started = time.perf_counter()
            interrupts.check()
            self._run_script()
            self.window.frame()  # input events: injected for the next step
            for _ in range(self._due_steps()):
                self._step_once = False
                if self._script_waits_here() or not self._one(steps):
                    break
            self._show()
            if self.result is not None:
                break
            time.sleep(max(0.0, FRAME - (time.perf_counter() - started)))
        while self.result is None:  # the window was closed: the rest without it
            interrupts.check()
            self._one(steps)
        return self.result

    def linger(self) -> None:
        """After the run: the window shows its end (verdicts, final state) until it is closed; with a
        script, until the script is done."""
        if self.result is not None:
            self.hud.verdicts = list(self.result.verdicts)
            self.hud.pending = 0
            self.hud.mode = "ended" if self.result.status != "engine-failure" else "engine failure"
            if self.result.failure:
                self.hud.note = self.result.failure[:160]
        self._over = True
        while not self.window.closed:
            started = time.perf_counter()
            interrupts.check()
            self._run_script()
            if self._scripted and not self.script:
                self.window.close()
                break
            self.window.frame()
            time.sleep(max(0.0, FRAME - (time.perf_counter() - started)))
        self.sounds.stop_all()
