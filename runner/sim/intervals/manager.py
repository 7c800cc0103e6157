"""Panda3D's interval manager (``ivalMgr``) and the play API of each interval, headless.

Sources: ``direct/src/interval/cIntervalManager.cxx``, ``IntervalManager.py``, ``cInterval.cxx``,
``Interval.py`` and ``MetaInterval.py`` (panda3d 1.10). What this reproduces:

* C++ intervals (Lerp, Wait, Sequence, Parallel) live in the manager under their *name*. Starting one
  whose name is taken by another object first **finishes** that object (it jumps to its end state,
  even if it never ran); a meta interval finished this way runs its Python children (Func, Sound) at
  the next :meth:`IntervalManager.step`, not inside ``start()``. ``is_playing``, ``pause`` and
  ``finish`` look the name up, so they see (and remove) whichever object holds it.
* Python intervals (a top-level Func or Sound) run as a task ``<name>-play``; starting one whose name
  has a task **pauses** the task's interval instead (no jump). Same-name C++ and Python intervals do
  not interact.
* :meth:`IntervalManager.step` is one frame: first the Python tasks (sort 0, in the order they were
  started: one started before ``step``, e.g. by a key handler, or during this phase runs in it, as
  measured on Panda3D; one started later in the frame waits for the next step), then every C++
  interval in name order (the later-sorting name wins a shared property; one started by a Func of a
  Sequence waits for the next step, at t = dt), then the meta intervals' queued Python events (those of
  intervals just finished first, then by manager slot), then the done events.

Each operation notifies ``host.interval_event(id, what, at)`` with what = started, paused, resumed,
finished, looped, taken_over (another object with the same name finished, paused or unregistered it)
or done (where Panda3D throws the interval's done event: C++ ones at the end of the step that ended
them, or of the next step after a start/finish; Python ones at once; never for a SoundInterval, a
Func, or a Lerp that began and ended in one frame).
"""

from __future__ import annotations

import bisect
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager

from runner.compile.interval_specs import (
    FuncSpec,
    IntervalSpec,
    LerpSpec,
    ParallelSpec,
    SequenceSpec,
    SoundSpec,
    WaitSpec,
)
from runner.sim.intervals.base import Node, State
from runner.sim.intervals.host import IntervalHost
from runner.sim.intervals.lerp import LerpLeaf, WaitLeaf
from runner.sim.intervals.meta import MetaTimeline
from runner.sim.intervals.play import Play
from runner.sim.intervals.pyleaves import FuncLeaf, SoundLeaf

__all__ = ["IntervalManager"]

_STATE_NAMES = ("initial", "started", "paused", "final")


class _Task:
    """A Python interval's ``<name>-play`` task."""

    __slots__ = ("alive", "play")

    def __init__(self, play: Play) -> None:
        self.play = play
        self.alive = True


class IntervalManager:
    """Panda3D's ``ivalMgr`` plus the play state of every interval of a scenario."""

    def __init__(self, host: IntervalHost, intervals: Mapping[str, tuple[str, IntervalSpec]]) -> None:
        self._host = host
        self._plays: dict[str, Play] = {}
        for ival, (name, spec) in intervals.items():
            play = Play(ival, name, self._build(spec), self._looped)
            play.root.on_done = self._done_callback(play)
            self._plays[ival] = play
        # CIntervalManager: name -> slot, the names in order, the slots, free and removed slots
        self._index: dict[str, int] = {}
        self._names: list[str] = []
        self._slots: list[Play | None] = []
        self._free: list[int] = []
        self._removed: list[int] = []
        self._tasks: list[_Task] = []  # Python intervals' tasks, in the order they were added
        self._task_of: dict[str, _Task] = {}
        self._done: list[tuple[str, float]] = []
        self._in_step = False

    def _build(self, spec: IntervalSpec) -> Node:
        host = self._host
        if isinstance(spec, LerpSpec):
            return LerpLeaf(host, spec)
        if isinstance(spec, (SequenceSpec, ParallelSpec)):
            return MetaTimeline(spec, self._build)
        if isinstance(spec, FuncSpec):
            return FuncLeaf(host, spec)
        if isinstance(spec, SoundSpec):
            return SoundLeaf(host, spec)
        if isinstance(spec, WaitSpec):
            return WaitLeaf(spec.duration)
        raise TypeError(f"Invalid interval spec. Expected one of the runner.sim.intervals specs. Received: {spec!r}")

    def _done_callback(self, play: Play) -> Callable[[float], None]:
        if play.is_python:
            return lambda at: self._host.interval_event(play.id, "done", at)
        return lambda at: self._done.append((play.id, at))

    def _looped(self, ival: str, at: float) -> None:
        self._host.interval_event(ival, "looped", at)

    def _play(self, ival: str) -> Play:
        play = self._plays.get(ival)
        if play is None:
            raise KeyError(f"Unknown interval {ival!r}. Known: {', '.join(sorted(self._plays))}")
        return play

    @contextmanager
    def _op(self, play: Play, now: float) -> Iterator[None]:
        """An operation at ``now`` on ``play`` (its events happen at ``now``), re-entrant."""
        saved = play.now, play.stepping
        play.now, play.stepping = now, False
        try:
            yield
        finally:
            play.now, play.stepping = saved

    # -- queries -------------------------------------------------------------------------------------

    def is_playing(self, ival: str) -> bool:
        """By Panda3D name, as Panda3D does: True for a taken-over object while its name plays."""
        play = self._play(ival)
        return play.name in (self._task_of if play.is_python else self._index)

    def state(self, ival: str) -> str:
        """initial | started | paused | final."""
        return _STATE_NAMES[self._play(ival).root.state]

    def get_t(self, ival: str) -> float:
        return self._play(ival).root.curr_t

    def get_duration(self, ival: str) -> float:
        return self._play(ival).root.duration

    # -- control ---------------------------------------------------------------------------------------

    def start(self, ival: str, now: float, start_t: float = 0.0, end_t: float | None = None, rate: float = 1.0) -> None:
        """``start(startT, endT, playRate)``: applies nothing; the next step plays from ``start_t``."""
        self._begin(ival, now, start_t, -1.0 if end_t is None else end_t, rate, do_loop=False)
        self._host.interval_event(ival, "started", now)

    def loop(self, ival: str, now: float) -> None:
        """``loop()``: at the end, the next step restarts from 0 at the overflow time."""
        self._begin(ival, now, 0.0, -1.0, 1.0, do_loop=True)
        self._host.interval_event(ival, "started", now)

    def _begin(self, ival: str, now: float, start_t: float, end_t: float, rate: float, do_loop: bool) -> None:
        play = self._play(ival)
        with self._op(play, now):
            play.setup_play(now, start_t, end_t, rate, do_loop)
            if play.is_python:
                self._spawn_task(play, now)
            else:
                self._add_c(play, now)

    def pause(self, ival: str, now: float) -> float:
        """``pause()``: interrupt (active sounds stop), leave the manager by name; returns ``getT()``."""
        play = self._play(ival)
        root = play.root
        with self._op(play, now):
            if root.state == State.STARTED:
                root.priv_interrupt(now)
            if play.is_python:
                self._remove_task(play, now)
            else:
                self._remove_by_name(play, now)
                if play.meta is not None:
                    play.meta.service()
        self._host.interval_event(ival, "paused", now)
        return root.curr_t

    def resume(self, ival: str, now: float, t: float | None = None) -> None:
        """``resume()`` / ``resume(t)``: continue from the current (or given) t; first step at that t."""
        play = self._play(ival)
        with self._op(play, now):
            if t is not None:
                self._set_t(play, t, now)
            play.setup_resume(now)
            if not play.is_python:
                self._add_c(play, now)
            elif play.name not in self._task_of:
                self._spawn_task(play, now)
        self._host.interval_event(ival, "resumed", now)

    def finish(self, ival: str, now: float) -> None:
        """``finish()``: jump to the end state, run the remaining action steps in order, stop."""
        play = self._play(ival)
        with self._op(play, now):
            root = play.root
            if isinstance(root, SoundLeaf):
                root.in_finish = True
            self._finish_root(play, now)
            if isinstance(root, SoundLeaf):
                root.in_finish = False
            if play.is_python:
                self._remove_task(play, now)
            else:
                self._remove_by_name(play, now)
                if play.meta is not None:
                    play.meta.service()
        self._host.interval_event(ival, "finished", now)

    @staticmethod
    def _finish_root(play: Play, now: float) -> None:
        """``CIntervalManager::finish_interval`` / ``finish()``'s state switch."""
        root = play.root
        if root.state == State.INITIAL:
            root.priv_instant(now)
        elif root.state != State.FINAL:
            root.priv_finalize(now)

    def _set_t(self, play: Play, t: float, now: float) -> None:
        """``setT(t)`` (``CInterval::set_t`` and ``privPostEvent``)."""
        root = play.root
        playing = play.name in (self._task_of if play.is_python else self._index)
        if root.state == State.INITIAL:
            root.priv_initialize(t, now)
            if playing:
                play.setup_resume(now)
            else:
                root.priv_interrupt(now)
        elif root.state == State.STARTED:
            root.priv_interrupt(now)
            root.priv_step(t, now)
            play.setup_resume(now)
        elif root.state == State.PAUSED:
            root.priv_step(t, now)
            root.priv_interrupt(now)
        else:
            root.priv_reverse_initialize(t, now)
            if playing:
                play.setup_resume(now)
            else:
                root.priv_interrupt(now)
        if play.meta is not None:
            play.meta.service()

    # -- CIntervalManager slots ----------------------------------------------------------------------

    def _add_c(self, play: Play, now: float) -> None:
        """``add_c_interval``: finish and remove another object holding the name, then register."""
        name = play.name
        slot = self._index.get(name)
        if slot is not None:
            old = self._slots[slot]
            if old is play:
                return
            if old is not None:
                with self._op(old, now):
                    self._finish_root(old, now)
                self._unindex(name)
                self._release(slot, external=old.meta is not None)
                self._host.interval_event(old.id, "taken_over", now)
        slot = self._free.pop() if self._free else len(self._slots)
        if slot == len(self._slots):
            self._slots.append(play)
        else:
            self._slots[slot] = play
        self._index[name] = slot
        bisect.insort(self._names, name)

    def _unindex(self, name: str) -> None:
        del self._index[name]
        del self._names[bisect.bisect_left(self._names, name)]

    def _release(self, slot: int, external: bool) -> None:
        """``remove_index``: a meta interval's slot waits for its Python callbacks (``_removed``)."""
        if external:
            self._removed.append(slot)
        else:
            self._slots[slot] = None
            self._free.append(slot)

    def _remove_by_name(self, play: Play, now: float) -> None:
        """``remove_c_interval(find_c_interval(name))``: whichever object holds the name leaves."""
        slot = self._index.get(play.name)
        if slot is None:
            return
        holder = self._slots[slot]
        self._unindex(play.name)
        self._slots[slot] = None
        self._free.append(slot)
        if holder is not None and holder is not play:
            self._host.interval_event(holder.id, "taken_over", now)

    # -- Python tasks ------------------------------------------------------------------------------------

    def _spawn_task(self, play: Play, now: float) -> None:
        """``Interval.__spawnTask``: kill the task of that name (interrupting its interval), add ours."""
        self._remove_task(play, now)
        task = _Task(play)
        self._tasks.append(task)
        self._task_of[play.name] = task

    def _remove_task(self, play: Play, now: float) -> None:
        """``Interval.__removeTask``: the task's interval (maybe another object) is interrupted."""
        task = self._task_of.pop(play.name, None)
        if task is None:
            return
        task.alive = False
        other = task.play
        with self._op(other, now):
            other.root.priv_interrupt(now)
        if other is not play:
            self._host.interval_event(other.id, "taken_over", now)

    # -- the frame ---------------------------------------------------------------------------------------

    def step(self, now: float) -> None:
        """One frame at ``now``: Python tasks, C++ intervals in name order, Python callbacks, done events."""
        if not (self._tasks or self._names or self._slots or self._removed or self._done):
            return  # no interval has been started: nothing to step
        if self._in_step:
            raise RuntimeError("IntervalManager.step() called from inside step()")
        self._in_step = True
        try:
            self._step_tasks(now)
            self._step_c(now)
            self._python_callbacks()
            while self._done:
                done, self._done = self._done, []
                for ival, at in done:
                    self._host.interval_event(ival, "done", at)
        finally:
            self._in_step = False

    @staticmethod
    def _step_play(play: Play, now: float) -> bool:
        saved = play.now, play.stepping
        play.now, play.stepping = now, True
        try:
            return play.step_play(now)
        finally:
            play.now, play.stepping = saved

    def _step_tasks(self, now: float) -> None:
        tasks = self._tasks
        i = 0
        while i < len(tasks):  # a task added by one of these runs in this phase too
            task = tasks[i]
            i += 1
            if task.alive and not self._step_play(task.play, now):
                task.alive = False
                if self._task_of.get(task.play.name) is task:
                    del self._task_of[task.play.name]
        if any(not task.alive for task in tasks):
            self._tasks = [task for task in tasks if task.alive]

    def _step_c(self, now: float) -> None:
        for name in tuple(self._names):
            slot = self._index.get(name)
            play = None if slot is None else self._slots[slot]
            if play is not None and slot is not None and not self._step_play(play, now):
                self._unindex(name)
                self._release(slot, external=play.meta is not None)

    def _python_callbacks(self) -> None:
        """``IntervalManager.__doPythonCallbacks``: removed intervals first, then by slot."""
        while self._removed:
            slot = self._removed.pop()
            play = self._slots[slot]
            self._slots[slot] = None
            self._free.append(slot)
            if play is not None and play.meta is not None:
                play.meta.service()
        slot = 0
        while slot < len(self._slots):
            play = self._slots[slot]
            if play is not None and play.meta is not None and play.meta.has_pending:
                play.meta.service()
            slot += 1
