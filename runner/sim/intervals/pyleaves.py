"""The Python leaves: ``FunctionInterval`` (Func) and ``SoundInterval``.

Both are ``Interval.Interval`` subclasses (``direct/src/interval/FunctionInterval.py``,
``SoundInterval.py``): a meta interval cannot run them itself but hands their events to Python,
after its C++ work of the frame, and a top-level one runs as its own task ``<name>-play`` at sort 0,
before ``ivalMgr.step()``. Their overrides have quirks that the runner reproduces on purpose:

* ``FunctionInterval.privInstant`` only calls the function: the state is left as it was (a Func
  run by its task stays ``initial``), no done event. Any other transition is the base class's, so a
  Func that was paused (interrupted by a same-name start) and then played again is *finalized*
  without calling its function.
* ``SoundInterval.privInstant`` does nothing (a sound skipped within one frame never plays);
  ``privInitialize`` plays from ``t + startTime`` (0 when below 0.1 s) unless that is past the sound's
  length, and does not restart a sound it is already playing (seamless loop); ``privStep`` restarts it
  only when coming back from a pause (no 0.1 s rounding); ``privInterrupt`` stops it;
  ``privFinalize`` stops it and sends no done event, except at the end of each cycle of a top-level
  ``loop()`` (the sound keeps looping, the interval stays ``started``).
"""

from __future__ import annotations

from runner.compile.interval_specs import FuncSpec, SoundSpec
from runner.sim.intervals.base import Node, State
from runner.sim.intervals.host import IntervalHost

__all__ = ["FuncLeaf", "SoundLeaf"]


class FuncLeaf(Node):
    """``Func(f)``: duration 0, open-ended; ``privInstant`` calls ``host.run_actions``."""

    is_python = True

    def __init__(self, host: IntervalHost, spec: FuncSpec) -> None:
        super().__init__(0.0)
        self.host = host
        self.spec = spec

    def priv_instant(self, at: float) -> None:
        self.host.run_actions(self.spec.actions, at)


class SoundLeaf(Node):
    """``SoundInterval`` (seamlessLoop=True, no node, no listener, no cut-off)."""

    is_python = True

    def __init__(self, host: IntervalHost, spec: SoundSpec) -> None:
        super().__init__(spec.duration)
        self.host = host
        self.spec = spec
        self.length = spec.sound_length  # sound.length(), read once at construction
        self.f_loop = spec.loop  # the sound's own loop flag (loop() of a top-level one sets it)
        self.do_loop = False  # Interval.getLoop(): only a top-level loop() sets it
        self.in_finish = False  # SoundInterval.finish() sets _inFinish around privFinalize
        self._playing = False  # _soundPlaying
        self._may_sound = False  # this interval started the sound and has not stopped it since

    def on_setup_play(self, do_loop: bool) -> None:
        if do_loop:
            self.f_loop = True
        self.do_loop = do_loop

    def _play(self, offset: float, at: float) -> None:
        spec = self.spec
        self.host.play_sound(spec.sound, offset, spec.volume, self.f_loop, at)
        self._may_sound = True

    def _stop(self, at: float) -> None:
        # Panda3D calls sound.stop() whether or not it plays; a stop that cannot change anything
        # (nothing played by this interval since its last stop) is not passed on.
        self._playing = False
        if self._may_sound:
            self._may_sound = False
            self.host.stop_sound(self.spec.sound, at)

    def priv_initialize(self, t: float, at: float) -> None:
        t1 = t + self.spec.start_time
        if t1 < 0.1:
            t1 = 0.0
        if t1 < self.length and not self._playing:
            self._play(t1, at)
            self._playing = True
        self.state = State.STARTED
        self.curr_t = t

    def priv_instant(self, at: float) -> None:
        return

    def priv_step(self, t: float, at: float) -> None:
        if self.state == State.PAUSED:
            t1 = t + self.spec.start_time
            if t1 < self.length:
                self._play(t1, at)  # Panda3D leaves _soundPlaying as it is here
        self.state = State.STARTED
        self.curr_t = t

    def priv_finalize(self, at: float) -> None:
        if self._playing and self.do_loop and not self.in_finish:
            return  # a seamless loop: the audio system keeps looping it
        self._stop(at)
        self.curr_t = self.duration
        self.state = State.FINAL

    def priv_reverse_initialize(self, t: float, at: float) -> None:
        return  # only sets _reverse, which nothing reads

    def priv_reverse_instant(self, at: float) -> None:
        self.state = State.INITIAL

    def priv_reverse_finalize(self, at: float) -> None:
        self.state = State.INITIAL

    def priv_interrupt(self, at: float) -> None:
        self._stop(at)
        self.state = State.PAUSED
