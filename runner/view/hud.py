"""The heads-up text of the window: time, last events, sounds playing, verdicts as they are decided.

Plain data and plain strings (no Panda3D here), so what the window says can be tested on its own. The
window draws :meth:`Hud.lines` in its top-left corner every frame.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from runner.view.keys import HELP_LINES

__all__ = ["Hud", "fmt_speed"]

LAST_EVENTS = 5
LAST_VERDICTS = 3


def fmt_speed(speed: float) -> str:
    return f"x{speed:g}" if speed >= 1 else f"x1/{1 / speed:g}"


@dataclass
class Hud:
    """What the heads-up lines show; the live run and the replay fill it in."""

    title: str
    end_time: float
    time: float = 0.0
    speed: float = 1.0
    mode: str = "running"  # running | paused | ended | replay
    events: deque[tuple[float, str]] = field(default_factory=lambda: deque(maxlen=LAST_EVENTS))
    sounds: dict[str, float] = field(default_factory=dict)  # playing: name -> start time
    verdicts: list[Any] = field(default_factory=list)  # decided, in the order decided (runner.sim Verdict)
    pending: int = 0  # verdicts not decided yet
    queued: list[str] = field(default_factory=list)  # inputs waiting for the next step boundary
    recording: str = ""  # the variant name of --record
    played: int = 0
    show_help: bool = False
    note: str = ""

    def event(self, t: float, text: str) -> None:
        self.events.append((t, text))

    def _verdict_line(self) -> str:
        passed = sum(1 for v in self.verdicts if v.passed)
        failed = len(self.verdicts) - passed
        line = f"verdicts: {passed} pass, {failed} FAIL, {self.pending} to come"
        recent = [f"{'pass' if v.passed else 'FAIL'} {v.name}" for v in self.verdicts[-LAST_VERDICTS:]]
        return line + ("  |  " + "  ".join(recent) if recent else "")

    def lines(self) -> list[str]:
        head = f"t {self.time:6.2f} / {self.end_time:.2f} s  {fmt_speed(self.speed)}  {self.mode}   {self.title}"
        events = "  ".join(f"{t:.2f} {name}" for t, name in self.events) or "-"
        sounds = "  ".join(sorted(self.sounds)) or "-"
        out = [head, f"events: {events}", f"sounds: {sounds}", self._verdict_line()]
        if self.queued:
            out.append("next step: " + " ".join(self.queued))
        if self.recording:
            out.append(f"recording variant '{self.recording}': {self.played} input(s) so far (written on close)")
        if self.note:
            out.append(self.note)
        out += list(HELP_LINES) if self.show_help else ["F1 help"]
        return out


def verdict_summary(verdicts: Sequence[Any]) -> str:
    passed = sum(1 for v in verdicts if v.passed)
    return f"{passed}/{len(verdicts)} passed"
