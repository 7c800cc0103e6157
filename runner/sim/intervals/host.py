"""The interval manager's view of the run: body poses to read and write, actions and sounds to fire."""

from __future__ import annotations

from typing import Any, Protocol

from runner.compile.interval_specs import Vec3


class IntervalHost(Protocol):
    """Implemented by the runner. Every ``at`` is a simulated time no later than the current ``now``."""

    def get_pos(self, body: str) -> Vec3: ...

    def get_hpr(self, body: str) -> Vec3: ...  # as last set (Panda3D getHpr returns what was set)

    def get_scale(self, body: str) -> float: ...

    def set_pos(self, body: str, pos: Vec3) -> None: ...

    def set_hpr(self, body: str, hpr: Vec3) -> None: ...

    def set_scale(self, body: str, scale: float) -> None: ...

    def run_actions(self, actions: Any, at: float) -> None: ...  # a Func fired

    def play_sound(self, sound: str, offset: float, volume: float, loop: bool, at: float) -> None: ...

    def stop_sound(self, sound: str, at: float) -> None: ...

    # started/paused/resumed/finished/looped/taken_over/done
    def interval_event(self, ival: str, what: str, at: float) -> None: ...
