"""Sequence and Parallel: ``CMetaInterval``'s flattened integer timeline.

Source: ``direct/src/interval/cMetaInterval.cxx`` and ``MetaInterval.py``. Nested Sequences and
Parallels are flattened into one list of children with integer begin/end times (milliseconds); each
child gives a *begin* and an *end* event, or one *instant* event when its duration rounds to 0 (a
Func), and a Wait none. Events are stable-sorted by time. Stepping to ``t`` runs every event with
time <= t: a child whose begin and end both fall in one step gets ``priv_instant`` (jumps to its end),
still-active children ``priv_step(t - begin)``, new ones ``priv_initialize(t - begin)``; stepping back
undoes events in reverse (Funcs are not called backwards). Events of Python children (Func, Sound),
and of any child queued behind one, wait in the event queue until :meth:`MetaTimeline.service` (the
manager calls it after its C++ pass, or at once for pause/finish), as ``__doPythonCallbacks`` does.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Final

from runner.compile.interval_specs import FuncSpec, IntervalSpec, ParallelSpec, SequenceSpec, WaitSpec
from runner.sim.intervals.base import Ev, Node, State, from_ms, to_ms

__all__ = ["MetaTimeline"]

_BEGIN: Final = 0
_END: Final = 1
_INSTANT: Final = 2
_DONE: Final = -2  # a queue entry for the meta interval's own done event (enqueue_done_event)


class _Event:
    """``CMetaInterval::PlaybackEvent``."""

    __slots__ = ("begin", "kind", "n", "time")

    def __init__(self, time: int, n: int, kind: int) -> None:
        self.time = time
        self.n = n
        self.kind = kind
        self.begin = self


class MetaTimeline(Node):
    """One top-level Sequence/Parallel with its children flattened (one ``CMetaInterval``).

    ``clock(ticks)`` turns a timeline time into the simulated time of an event (``at``); the
    manager's play state provides it.
    """

    def __init__(self, spec: SequenceSpec | ParallelSpec, build_leaf: Callable[[IntervalSpec], Node]) -> None:
        super().__init__(0.0)
        self.children: list[Node] = []
        self.begins: list[int] = []  # each child's begin time (ticks)
        self.events: list[_Event] = []
        end = self._flatten(spec, 0, build_leaf)
        self.events.sort(key=_event_time)  # stable: insertion order at ties
        self.duration = from_ms(end)
        self.clock: Callable[[int], float] = from_ms
        self._active: deque[_Event] = deque()
        self._next = 0
        self._queue: deque[tuple[int, Ev, int, float]] = deque()

    def _flatten(
        self, spec: SequenceSpec | ParallelSpec, level_begin: int, build: Callable[[IntervalSpec], Node]
    ) -> int:
        """``recompute_level``: add the level's children, return the level's end time."""
        level_end = prev_end = level_begin
        sequential = isinstance(spec, SequenceSpec)
        for child in spec.children:
            begin = prev_end if sequential else level_begin
            if isinstance(child, (SequenceSpec, ParallelSpec)):
                end = self._flatten(child, begin, build)
            else:
                end = begin + (0 if isinstance(child, FuncSpec) else to_ms(child.duration))
                if not isinstance(child, WaitSpec):
                    self._add_child(build(child), begin, end)
            prev_end = end
            level_end = max(level_end, end)
        if spec.duration is not None:
            level_end = level_begin + to_ms(spec.duration)
        return level_end

    def _add_child(self, node: Node, begin: int, end: int) -> None:
        n = len(self.children)
        self.children.append(node)
        self.begins.append(begin)
        if begin == end:
            self.events.append(_Event(begin, n, _INSTANT))
        else:
            first, last = _Event(begin, n, _BEGIN), _Event(end, n, _END)
            last.begin = first
            self.events += (first, last)

    # -- the event queue ---------------------------------------------------------------------------

    @property
    def has_pending(self) -> bool:
        return bool(self._queue)

    def _enqueue(self, n: int, ev: Ev, is_initial: bool, time: int, at: float) -> None:
        """``enqueue_event``: a C++ child runs now unless Python events are waiting before it."""
        child = self.children[n]
        if is_initial and (ev == Ev.INSTANT or ev == Ev.REVERSE_INSTANT) and not child.open_ended:
            return
        if not child.is_python and not self._queue:
            child.do_event(ev, from_ms(time), at)
            return
        self._queue.append((n, ev, time, at))

    def _done(self, at: float) -> None:
        if self._queue:
            self._queue.append((_DONE, Ev.FINALIZE, 0, at))
        else:
            self.interval_done(at)

    def service(self) -> None:
        """Run the queued events in order (``__doPythonCallbacks`` + ``service_event_queue``)."""
        queue = self._queue
        while queue:
            n, ev, time, at = queue.popleft()
            if n == _DONE:
                self.interval_done(at)
            else:
                self.children[n].do_event(ev, from_ms(time), at)

    # -- forward / reverse event walks ---------------------------------------------------------------

    def _forward(self, event: _Event, new_active: list[_Event], is_initial: bool) -> None:
        if event.kind == _BEGIN:
            new_active.append(event)
        elif event.kind == _END:
            begin = event.begin
            if begin in new_active:  # began within this step: instant
                new_active.remove(begin)
                self._enqueue(event.n, Ev.INSTANT, is_initial, 0, self.clock(begin.time))
            elif begin in self._active:  # (Panda3D logs "not on active list" otherwise)
                self._active.remove(begin)
                self._enqueue(event.n, Ev.FINALIZE, is_initial, 0, self.clock(event.time))
        else:
            self._enqueue(event.n, Ev.INSTANT, is_initial, 0, self.clock(event.time))

    def _finish_forward(self, now: int, new_active: list[_Event]) -> None:
        at_now = self.clock(now)
        for event in self._active:
            self._enqueue(event.n, Ev.STEP, False, now - event.time, at_now)
        for event in new_active:
            self._enqueue(event.n, Ev.INITIALIZE, False, now - event.time, self.clock(event.time))
            self._active.append(event)

    def _reverse(self, event: _Event, new_active: deque[_Event], is_initial: bool) -> None:
        if event.kind == _BEGIN:
            at = self.clock(event.time)
            if event in new_active:
                new_active.remove(event)
                self._enqueue(event.n, Ev.REVERSE_INSTANT, is_initial, 0, at)
            elif event in self._active:
                self._active.remove(event)
                self._enqueue(event.n, Ev.REVERSE_FINALIZE, is_initial, 0, at)
        elif event.kind == _END:
            new_active.appendleft(event.begin)
        else:
            self._enqueue(event.n, Ev.REVERSE_INSTANT, is_initial, 0, self.clock(event.time))

    def _finish_reverse(self, now: int, new_active: deque[_Event]) -> None:
        at_now = self.clock(now)
        for event in self._active:
            self._enqueue(event.n, Ev.STEP, False, now - event.time, at_now)
        for event in new_active:
            self._enqueue(event.n, Ev.REVERSE_INITIALIZE, False, now - event.time, at_now)
            self._active.appendleft(event)

    def _walk_forward(self, now: int | None, is_initial: bool) -> None:
        """Run the events up to ``now`` (all of them if None), then step/initialize the active ones."""
        events: list[_Event] = self.events
        new_active: list[_Event] = []
        limit = len(events)
        while self._next < limit and (now is None or events[self._next].time <= now):
            event = events[self._next]
            self._next += 1
            self._forward(event, new_active, is_initial)
        self._finish_forward(to_ms(self.duration) if now is None else now, new_active)

    def _walk_reverse(self, now: int, is_initial: bool, everything: bool = False) -> None:
        """Undo the events after ``now`` (all of them if ``everything``), then step the active ones."""
        events: list[_Event] = self.events
        new_active: deque[_Event] = deque()
        while self._next > 0 and (everything or events[self._next - 1].time > now):
            self._next -= 1
            self._reverse(events[self._next], new_active, is_initial)
        self._finish_reverse(now, new_active)

    # -- CInterval overrides -------------------------------------------------------------------------

    def priv_initialize(self, t: float, at: float) -> None:
        self._next = 0
        self._active.clear()
        self._walk_forward(to_ms(t), True)
        self.curr_t = t
        self.state = State.STARTED

    def priv_instant(self, at: float) -> None:
        self._active.clear()
        for event in self.events:
            if event.kind != _BEGIN:
                self._enqueue(event.n, Ev.INSTANT, True, 0, at)
        self._next = len(self.events)
        self.curr_t = self.duration
        self.state = State.FINAL
        self._done(at)

    def priv_step(self, t: float, at: float) -> None:
        now = to_ms(t)
        if self._next < len(self.events) and self.events[self._next].time <= now:
            self._walk_forward(now, False)
        else:
            self._walk_reverse(now, False)
        self.curr_t = t
        self.state = State.STARTED

    def priv_finalize(self, at: float) -> None:
        if self.state == State.INITIAL:
            self.priv_initialize(self.duration, at)
        self._walk_forward(None, True)
        self.curr_t = self.duration
        self.state = State.FINAL
        self._done(at)

    def priv_reverse_initialize(self, t: float, at: float) -> None:
        self._next = len(self.events)
        self._active.clear()
        self._walk_reverse(to_ms(t), True)
        self.curr_t = t
        self.state = State.STARTED

    def priv_reverse_instant(self, at: float) -> None:
        self._active.clear()
        for event in reversed(self.events):
            if event.kind != _BEGIN:
                self._enqueue(event.n, Ev.REVERSE_INSTANT, True, 0, at)
        self._next = 0
        self.curr_t = 0.0
        self.state = State.INITIAL

    def priv_reverse_finalize(self, at: float) -> None:
        if self.state == State.INITIAL:
            self.priv_initialize(0.0, at)
        self._walk_reverse(0, True, everything=True)
        self.curr_t = 0.0
        self.state = State.INITIAL

    def priv_interrupt(self, at: float) -> None:
        for event in self._active:
            self._enqueue(event.n, Ev.INTERRUPT, False, 0, at)
        if self.state == State.STARTED:
            self.state = State.PAUSED


def _event_time(event: _Event) -> int:
    return event.time
