"""One top-level interval's playback clock: ``CInterval::setup_play``/``setup_resume``/``step_play``.

``start(now)`` only records ``clock_start = now``; each ``step_play(now)`` computes
``t = (now - clock_start)*rate + start_t`` and initialises, steps or finalises the interval
(``direct/src/interval/cInterval.cxx``; ``Interval.stepPlay`` is the same logic). Play time is
compared with :data:`~runner.sim.intervals.base.TIME_EPS` of tolerance.

``at_of(t)`` gives the simulated time of a timeline event at ``t``: during a step, its scheduled time
``clock_start + (t - start_t)/rate`` (never later than ``now``); during any other operation
(start, pause, resume, finish), that operation's ``now``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from runner.sim.intervals.base import TIME_EPS, Node, State, from_ms
from runner.sim.intervals.meta import MetaTimeline

__all__ = ["Play"]


class Play:
    """The play state of one interval id: its root node, its Panda3D name and its clock."""

    def __init__(self, ival: str, name: str, root: Node, on_loop: Callable[[str, float], None]) -> None:
        self.id = ival
        self.name = name
        self.root = root
        self.is_python = root.is_python
        self.meta = root if isinstance(root, MetaTimeline) else None
        self._on_loop = on_loop
        self.clock_start = 0.0
        self.start_t = 0.0
        self.end_t = root.duration
        self.start_t_at_start = True
        self.end_t_at_end = True
        self.rate = 1.0
        self.do_loop = False
        self.loop_count = 0
        self.now = 0.0  # the current operation's time
        self.stepping = False  # inside step_play: events get their scheduled times
        if self.meta is not None:
            self.meta.clock = self._clock

    def at_of(self, t: float) -> float:
        if not self.stepping:
            return self.now
        if self.rate > 0.0:
            at = self.clock_start + (t - self.start_t) / self.rate
        else:
            at = self.clock_start + (t - self.end_t) / self.rate
        return at if at < self.now else self.now

    def _clock(self, ticks: int) -> float:
        return self.at_of(from_ms(ticks))

    def setup_play(self, now: float, start_t: float, end_t: float, rate: float, do_loop: bool) -> None:
        if rate == 0.0 or not math.isfinite(rate):
            raise ValueError(
                f"Invalid `rate` for interval {self.id!r}. Expected a finite non-zero number. Received: rate={rate!r}"
            )
        if not (end_t < 0.0 or start_t < end_t):
            raise ValueError(
                f"Invalid `end_t` for interval {self.id!r}. Expected end_t > start_t. "
                f"Received: start_t={start_t!r}, end_t={end_t!r}"
            )
        duration = self.root.duration
        if start_t <= 0.0:
            self.start_t, self.start_t_at_start = 0.0, True
        else:
            self.start_t, self.start_t_at_start = min(start_t, duration), False
        if end_t < 0.0 or end_t >= duration:
            self.end_t, self.end_t_at_end = duration, True
        else:
            self.end_t, self.end_t_at_end = end_t, False
        self.clock_start = now
        self.rate = rate
        self.do_loop = do_loop
        self.loop_count = 0
        self.root.on_setup_play(do_loop)

    def setup_resume(self, now: float) -> None:
        ref = self.start_t if self.rate > 0.0 else self.end_t
        self.clock_start = now - (self.root.curr_t - ref) / self.rate
        self.loop_count = 0

    def step_play(self, now: float) -> bool:
        """Advance to ``now``; False when the interval is done and leaves the manager."""
        root = self.root
        elapsed = now - self.clock_start
        if self.rate > 0.0:
            if self.end_t_at_end:
                self.end_t = root.duration
            t = elapsed * self.rate + self.start_t
            if t < self.end_t - TIME_EPS:
                self._play_to(t, reverse=False)
            else:
                if self.end_t_at_end:
                    if root.is_stopped():
                        if root.open_ended or self.loop_count != 0:
                            root.priv_instant(self.at_of(self.end_t))
                    else:
                        root.priv_finalize(self.at_of(self.end_t))
                else:
                    self._play_to(self.end_t, reverse=False)
                self._next_cycle(elapsed)
        else:
            t = elapsed * self.rate + self.end_t
            if t >= self.start_t - TIME_EPS:
                self._play_to(t, reverse=True)
            else:
                if self.start_t_at_start:
                    if root.is_stopped():
                        if root.open_ended or self.loop_count != 0:
                            root.priv_reverse_instant(self.at_of(self.start_t))
                    else:
                        root.priv_reverse_finalize(self.at_of(self.start_t))
                else:
                    self._play_to(self.start_t, reverse=True)
                self._next_cycle(elapsed)
        should_continue = self.loop_count == 0 or self.do_loop
        if not should_continue and root.state == State.STARTED:
            root.priv_interrupt(self.at_of(root.curr_t))
        return should_continue

    def _play_to(self, t: float, reverse: bool) -> None:
        root = self.root
        if not root.is_stopped():
            root.priv_step(t, self.now)
        elif reverse:
            root.priv_reverse_initialize(t, self.at_of(self.end_t))
        else:
            root.priv_initialize(t, self.at_of(self.start_t))

    def _next_cycle(self, elapsed: float) -> None:
        """Count the cycles run past and move the clock to the current one."""
        if self.end_t == self.start_t:
            self.loop_count += 1
        else:
            per_loop = (self.end_t - self.start_t) / abs(self.rate)
            cycles = max(1, math.floor((elapsed + TIME_EPS) / per_loop))
            self.loop_count += cycles
            self.clock_start += cycles * per_loop
        if self.do_loop:
            self._on_loop(self.id, min(self.clock_start, self.now))
