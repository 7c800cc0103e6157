"""``scenario view TRACE.mcap [TRACE ...]``: recorded runs replayed side by side, with a time slider.

Each trace gets its own region of the window and its own :class:`reports.scene3d.PandaScene`, built from
the trace alone by :func:`reports.scene3d.scene_model` (the report's pictures read it the same way); one
orbit camera moves them all, framed on every run's moving bodies (``camera="lab"``: the lab's). The
replay opens playing (``paused=True``: paused). The slider (or ``arrow_left``/``arrow_right``, one recorded
step; ``home``/``end``) sets the time and pauses; ``space`` or F3 plays and pauses, F4 steps, F5/F6 change
the speed. The heads-up lines show each run's events, sounds playing and verdicts decided up to the time shown.

The slider's callback comes from Panda3D's event queue, a frame after the value is set: it is told from a
person's drag by the value itself (the slider holds the last time the replay put there, to float32
precision, unless someone moved it), never by a flag raised around the assignment.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from reports import trace_format as tf
from reports.scene3d.model import SceneModel, scene_model
from reports.trace_reader import Trace, read_trace
from runner import interrupts
from runner.view.hud import Hud
from runner.view.live import FRAME, MAX_SPEED, MIN_SPEED
from runner.view.script import ScriptEntry

__all__ = ["Replay", "label_of"]

#: the slider keeps its value as a float32 (Panda3D's PN_stdfloat): a value within this fraction of the
#: replay's length (1e-5, a hundred times float32's precision, far below a pixel of the slider) is the
#: replay's own
SLIDER_ECHO = 1e-5


def label_of(trace: Trace) -> str:
    """The line under a run's picture: backend, how the run ended, verdicts passed."""
    passed = sum(1 for v in trace.verdicts if v.passed)
    return f"{trace.scenario.get(tf.KEY_BACKEND, '?')}: {trace.status}, {passed}/{len(trace.verdicts)} passed"


@dataclass
class _Run:
    trace: Trace
    model: SceneModel
    backend: str
    verdicts: list[tuple[float, str, bool]]  # (decided at, name, passed)


def _verdicts(trace: Trace) -> list[tuple[float, str, bool]]:
    """(decided at, name, passed) of every verdict (recorded at the end, each with the time it was decided)."""
    out = []
    for v in trace.verdicts:
        when = v.data.get("time")
        out.append((float(when) if isinstance(when, int | float) else v.t, v.name, bool(v.passed)))
    return sorted(out, key=lambda v: v[0])


class Replay:
    """The window replaying ``paths``; :meth:`run` until it is closed."""

    def __init__(self, paths: Sequence[Path], *, offscreen: bool = False, at: float = 0.0, paused: bool = False,
                 speed: float = 1.0, script: Sequence[ScriptEntry] = (), camera: str = "auto") -> None:  # fmt: skip
        from reports.scene3d.framing import LAB_CAMERA, frame_camera
        from reports.scene3d.panda import PandaScene
        from runner.view.window import ViewWindow

        traces = [read_trace(p) for p in paths]
        self.runs = [
            _Run(t, scene_model(t), t.scenario.get(tf.KEY_BACKEND, "?"), _verdicts(t)) for t in traces
        ]
        self.end = max((r.model.end_time for r in self.runs), default=0.0)
        self.times = np.unique(np.concatenate([r.trace.times for r in self.runs])) if self.runs else np.zeros(1)
        first = traces[0].scenario
        title = f"scenario view: {first.get(tf.KEY_NAME, '?')} / {first.get(tf.KEY_VARIANT, '?')} (replay)"
        self.hud = Hud(title=title, end_time=self.end, mode="replay")
        scenes = [PandaScene(r.model) for r in self.runs]
        starts = [r.model.pose(b, 0.0) for r in self.runs for b in r.model.bodies if r.model.shape.get(b) != "plane"]
        targets = [p[0].tolist() for p in starts if p is not None]
        cam = LAB_CAMERA if camera == "lab" else frame_camera([r.model for r in self.runs]).with_aspect(4 / 3)
        self.window = ViewWindow(title, scenes, self.hud, offscreen=offscreen, targets=targets, camera=cam,
                                 labels=[label_of(r.trace) for r in self.runs])  # fmt: skip
        self.window.on_input = self.on_input
        self.window.on_action = self.on_action
        self.t = min(max(at, 0.0), self.end)
        self.playing = not paused
        self.speed = min(MAX_SPEED, max(MIN_SPEED, speed))
        self.script = list(script)
        self._scripted = bool(script)
        self._on_slider = self.t  # the time the replay last put on the slider
        self.slider = self._slider()

    def _slider(self) -> Any:
        from direct.gui.DirectSlider import DirectSlider

        return DirectSlider(parent=self.window.base.a2dBottomCenter, range=(0.0, max(self.end, 1e-6)),
                            value=self.t, pageSize=max(self.end / 20, 1e-3), scale=(1.1, 1, 0.5),
                            pos=(0, 0, 0.08), command=self._slid)  # fmt: skip

    def _slid(self) -> None:
        """The slider moved: by a person (a value the replay did not put there: go there and pause), or by
        :meth:`_show`'s own assignment, whose callback arrives a frame later (nothing to do)."""
        value = float(self.slider.getValue())
        if abs(value - self._on_slider) <= SLIDER_ECHO * max(self.end, 1.0):
            return
        self.t = min(max(value, 0.0), self.end)
        self.playing = False

    def on_input(self, name: str) -> None:
        k = int(np.searchsorted(self.times, self.t + 1e-9, side="right")) - 1
        if name == "space":
            self.on_action("pause")
        elif name in ("arrow_left", "arrow_right"):
            k = min(max(k + (1 if name == "arrow_right" else -1), 0), len(self.times) - 1)
            self.t, self.playing = float(self.times[k]), False
        elif name in ("home", "end"):
            self.t, self.playing = (0.0 if name == "home" else self.end), False

    def on_action(self, action: str) -> None:
        if action in ("pause", "step"):
            self.playing = not self.playing if action == "pause" else False
            if action == "step":
                self.on_input("arrow_right")
            if self.playing and self.t >= self.end:
                self.t = 0.0
        elif action in ("slower", "faster"):
            self.speed = min(MAX_SPEED, max(MIN_SPEED, self.speed * (0.5 if action == "slower" else 2.0)))

    def _show(self) -> None:
        many = len(self.runs) > 1
        events: list[tuple[float, str]] = []
        sounds: dict[str, float] = {}
        decided = []
        for r in self.runs:
            tag = f"{r.backend}: " if many else ""
            events += [(e.t, tag + e.name) for e in r.trace.events if e.t <= self.t + 1e-9]
            for s in r.trace.sounds:
                if s.t <= self.t + 1e-9:
                    if s.action == "start":
                        sounds[tag + s.name] = s.t
                    else:
                        sounds.pop(tag + s.name, None)
            decided += [_Decided(tag + name, ok) for at, name, ok in r.verdicts if at <= self.t + 1e-9]
        events.sort(key=lambda e: e[0])
        self.hud.events.clear()
        self.hud.events.extend(events[-self.hud.events.maxlen :] if self.hud.events.maxlen else events)
        self.hud.sounds = sounds
        self.hud.verdicts = decided
        self.hud.pending = sum(len(r.verdicts) for r in self.runs) - len(decided)
        self.hud.time = self.t
        self.hud.speed = self.speed
        self.hud.mode = "replay, playing" if self.playing else "replay, paused"
        for scene in self.window.scenes:
            scene.show(self.t)
        if self.t != self._on_slider:
            self._on_slider = self.t
            self.slider["value"] = self.t

    def _run_script(self, now: float) -> None:
        for entry in list(self.script):
            if entry.after is not None and entry.after > now:
                continue
            if entry.at is not None and self.playing and entry.at > self.t + 1e-9:
                continue
            self.script.remove(entry)
            if entry.at is not None and not self.playing:
                self.t = min(entry.at, self.end)
            self._show()
            if entry.event:
                self.window.button(entry.event)
            elif entry.screenshot is not None:
                self.window.frame()
                self.window.screenshot(entry.screenshot)
            elif entry.close:
                self.window.close()
            return  # one entry per frame: each is seen drawn before the next

    def run(self) -> None:
        opened = last = time.perf_counter()
        while not self.window.closed:
            now = time.perf_counter()
            interrupts.check()
            if self.playing:
                self.t += (now - last) * self.speed
                if self.t >= self.end:
                    self.t, self.playing = self.end, False
            last = now
            self._show()
            self._run_script(now - opened)
            if self._scripted and not self.script:
                self.window.close()
                break
            self.window.frame()
            time.sleep(max(0.0, FRAME - (time.perf_counter() - now)))


@dataclass(frozen=True)
class _Decided:
    name: str
    passed: bool

