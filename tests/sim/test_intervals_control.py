"""Panda3D's interval control API (runner.sim.intervals) against notes/panda3d-semantics.md section 3.

start/pause/resume/finish/loop, Sequence and Parallel timing, SoundInterval, event times and the
time tolerance, driven as Panda3D's frame loop at dt = 0.04 (helpers in test_intervals.py).
"""

from __future__ import annotations

import pytest

from runner.sim.intervals import TIME_EPS, FuncSpec, IntervalManager, ParallelSpec, SequenceSpec, SoundSpec, WaitSpec

from .test_intervals import DT, Host, lerp, run

# --- §3 Interval control API ---------------------------------------------------------------------------


def test_start_applies_nothing_until_the_first_step() -> None:
    """§3 setup_play records the clock only; the first step (same frame) is at t=0."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"i": ("i", lerp(1.0, 10.0, start_pos=(5.0, 0.0, 0.0)))})
    mgr.start("i", 0.8)
    assert host.pos["b"] == (0.0, 0.0, 0.0) and mgr.state("i") == "initial"
    assert run(mgr, host, 0.8, 0.84) == pytest.approx([5.0, 5.2], abs=1e-12)


def test_pause_freezes_and_resume_continues_from_the_same_t() -> None:
    """§3 pause: stays, returns getT(), leaves the manager; resume: first step at the same t [checked]."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"i": ("i", lerp(1.0, 10.0))})
    mgr.start("i", 0.0)
    run(mgr, host, 0.0, 0.4)
    assert mgr.pause("i", 0.44) == pytest.approx(0.4, abs=1e-12)
    assert not mgr.is_playing("i") and mgr.state("i") == "paused"
    assert run(mgr, host, 0.44, 1.0) == [pytest.approx(4.0, abs=1e-12)] * 15
    mgr.resume("i", 2.0)
    assert run(mgr, host, 2.0, 2.08) == pytest.approx([4.0, 4.4, 4.8], abs=1e-12)
    mgr.resume("i", 2.12, t=0.9)  # resume(t) = setT(t) + resume: the body is set at once
    assert host.pos["b"][0] == pytest.approx(9.0, abs=1e-12)


def test_pause_stops_active_sounds_and_resume_restarts_them_at_their_offset() -> None:
    """§3 pause: priv_interrupt to each active child (SoundInterval stops); privStep restarts it."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec((lerp(0.2, 1.0), ParallelSpec((SoundSpec("hum", 1.0, start_time=0.5), lerp(1.0, 2.0)))))
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 10.0)
    run(mgr, host, 10.0, 10.4)
    # at its begin (0.2 s in), offset t + startTime
    assert host.entries("play") == [("hum", 0.5, pytest.approx(10.2), pytest.approx(10.2))]
    host.now = 10.44
    mgr.pause("s", 10.44)
    assert host.entries("stop") == [("hum", 10.44, 10.44)]
    host.now = 11.0
    mgr.resume("s", 11.0)
    run(mgr, host, 11.0, 11.0)  # paused at t=.4: the sound had played .2 s
    assert host.entries("play")[-1] == ("hum", pytest.approx(0.5 + 0.2), 11.0, 11.0)
    assert host.pos["b"][0] == pytest.approx(1.2, abs=1e-12)


def test_finish_jumps_to_the_end_and_runs_the_remaining_funcs_in_order() -> None:
    """§3 finish: object at end state, uncalled Funcs called in order, S_final, t = duration."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec((FuncSpec("f0"), lerp(0.2, 1.0), FuncSpec("f1"), WaitSpec(0.1), FuncSpec("f2"), lerp(0.2, 2.0)))
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 0.0)
    run(mgr, host, 0.0, 0.08)
    host.now = 0.1
    mgr.finish("s", 0.1)
    assert host.funcs() == ["f0", "f1", "f2"]
    assert host.pos["b"][0] == 2.0
    assert (mgr.state("s"), mgr.get_t("s"), mgr.is_playing("s")) == ("final", 0.5, False)
    assert [e[1] for e in host.entries("func")] == [0.0, 0.1, 0.1]  # finish's events happen at its `now`


def test_start_on_a_playing_sequence_rewinds_without_recalling_funcs_at_zero() -> None:
    """§3 start() on S_started: priv_step(0) sweeps back; Funcs at t=0 are not re-called [checked]."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec((FuncSpec("f0"), lerp(0.2, 1.0), FuncSpec("f1"), lerp(0.2, 2.0), FuncSpec("f2")))
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 0.0)
    run(mgr, host, 0.0, 0.28)
    assert host.funcs() == ["f0", "f1"]
    mgr.start("s", 0.32)
    assert run(mgr, host, 0.32, 0.72) == pytest.approx(
        [0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0], abs=1e-12
    )
    assert host.funcs() == ["f0", "f1", "f1", "f2"]


def test_start_with_a_time_range_and_rate() -> None:
    """§3 start(startT, endT, playRate): plays startT..endT at the rate, then stops, paused at endT."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"i": ("i", lerp(1.0, 10.0, start_pos=(0.0, 0.0, 0.0)))})
    mgr.start("i", 0.0, start_t=0.2, end_t=0.6, rate=2.0)
    assert run(mgr, host, 0.0, 0.28) == pytest.approx([2.0, 2.8, 3.6, 4.4, 5.2, 6.0, 6.0, 6.0], abs=1e-12)
    assert (mgr.state("i"), mgr.get_t("i"), mgr.is_playing("i")) == ("paused", 0.6, False)


def test_loop_restarts_at_the_overflow_time() -> None:
    """§3 loop(): the end frame shows the exact end, the next restarts at the overflow time.

    The notes' [checked] `0,.2,.4,.6,.8,1.0,1.0,.4,.6` is Panda3D when its float frame clock puts the
    fifth frame a hair before 0.2 s; with the clock a hair after (or exact, as here) Panda3D gives
    `...,1.0,.2,.4` (measured: 12 and 18 of 30 start phases). TIME_EPS makes the exact case count.
    """
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"i": ("i", lerp(0.2, 1.0, start_pos=(0.0, 0.0, 0.0)))})
    mgr.loop("i", 0.0)
    got = run(mgr, host, 0.0, 0.32)
    assert got == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 0.2, 0.4, 0.6], abs=1e-9)
    assert [e[2] for e in host.entries("event") if e[1] == "looped"] == [pytest.approx(0.2, abs=1e-12)]


def test_sequence_func_timing() -> None:
    """§3 [checked]: f0 at the first step, f1 when t >= .2, f2 at t >= .3, f3 at the last step."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec(
        (FuncSpec("f0"), lerp(0.2, 1.0), FuncSpec("f1"), WaitSpec(0.1), FuncSpec("f2"), lerp(0.2, 2.0), FuncSpec("f3"))
    )
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 1.0)
    run(mgr, host, 1.0, 1.6)
    frames = [(e[0], round(e[2] - 1.0, 6), round(e[1] - 1.0, 6)) for e in host.entries("func")]
    # (label, frame t, scheduled at): f2 is due at .3 and seen at the .32 frame; f3 at .5, seen at .52
    assert frames == [("f0", 0.0, 0.0), ("f1", 0.2, 0.2), ("f2", 0.32, 0.3), ("f3", 0.52, 0.5)]
    assert mgr.state("s") == "final" and mgr.get_duration("s") == 0.5


def test_parallel_children_start_together_and_the_shorter_holds() -> None:
    """§3 Parallel: all start at 0, duration = max, a shorter child holds its end value."""
    host = Host(a=(0.0, 0.0, 0.0), b=(0.0, 0.0, 0.0))
    par = ParallelSpec((lerp(0.4, 4.0, body="a"), lerp(0.2, 1.0, body="b")))
    mgr = IntervalManager(host, {"p": ("p", par)})
    mgr.start("p", 0.0)
    assert run(mgr, host, 0.0, 0.4, body="b") == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8] + [1.0] * 6, abs=1e-12)
    assert host.pos["a"][0] == 4.0 and mgr.get_duration("p") == 0.4 and mgr.state("p") == "final"


def test_children_skipped_within_one_step() -> None:
    """§3: begin and end within one step -> priv_instant (jump to end); Funcs skipped still called in order;
    a SoundInterval skipped that way never plays (privInstant does nothing) [checked]."""
    host = Host(a=(0.0, 0.0, 0.0), b=(0.0, 0.0, 0.0), c=(0.0, 0.0, 0.0))
    seq = SequenceSpec(
        (
            FuncSpec("f0"),
            lerp(0.01, 3.0, body="a"),
            SoundSpec("tick", 0.01, length=1.0),  # initialized, it would play from 0.48
            FuncSpec("f1"),
            lerp(0.2, 1.0),
            FuncSpec("f2"),
            lerp(2.0, 5.0, body="c"),
        )
    )
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 0.0)
    mgr.step(0.0)
    assert host.funcs() == ["f0"] and host.pos["a"][0] == 0.0
    host.now = 0.5
    mgr.step(0.5)  # one big step over the first five children
    assert mgr.state("s") == "started"
    assert host.funcs() == ["f0", "f1", "f2"]
    assert host.pos["a"][0] == 3.0 and host.pos["b"][0] == 1.0
    assert host.pos["c"][0] == pytest.approx(5.0 * (0.5 - 0.22) / 2.0, abs=1e-12)  # begun at 0.22
    assert host.entries("play") == [] and host.entries("stop") == []


def test_sound_interval_plays_at_its_begin_and_stops_at_its_end() -> None:
    """§3 SoundInterval: offset t + startTime (< 0.1 -> 0) at its begin; privFinalize stops it."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec((lerp(0.2, 1.0), SoundSpec("close", 0.3, start_time=0.06, volume=0.5)))
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 0.0)
    run(mgr, host, 0.0, 0.6)
    assert host.entries("play") == [("close", 0.0, pytest.approx(0.2), pytest.approx(0.2))]  # .06 < .1 -> 0
    assert host.entries("stop") == [("close", pytest.approx(0.5), pytest.approx(0.52))]


def test_event_times_are_scheduled_times_never_later_than_now() -> None:
    """`at` = clock_start + (event_t - start_t)/rate, clamped to `now`; ops happen at their `now`."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec((lerp(0.3, 1.0), FuncSpec("f")))
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 2.0, rate=2.0)  # 0.15 s of simulated time
    run(mgr, host, 2.0, 2.2)
    assert host.entries("func") == [("f", pytest.approx(2.15, abs=1e-12), pytest.approx(2.16))]


def test_meta_times_are_integer_milliseconds() -> None:
    """§3 double_to_int_time: floor(t*1000 + 0.5); a 0.2004 s child ends at 200 ms, 0.0004 s is instant."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec((lerp(0.2004, 1.0), FuncSpec("f1"), lerp(0.0004, 5.0), FuncSpec("f2")))
    mgr = IntervalManager(host, {"s": ("s", seq)})
    mgr.start("s", 0.0)
    run(mgr, host, 0.0, 0.16)
    assert host.funcs() == []
    run(mgr, host, 0.2, 0.2)
    assert host.funcs() == ["f1", "f2"] and host.pos["b"][0] == 5.0
    assert mgr.get_duration("s") == 0.2


def test_float_clocks_reach_the_end() -> None:
    """TIME_EPS: started at 8*0.04, the 2 s door lerp ends 50 steps later although 58*0.04 - 8*0.04 is
    1.9999999999999998 (without the tolerance it would end one step late)."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"i": ("door", lerp(2.0, 1.0, blend="easeInOut"))})
    mgr.start("i", 8 * DT)
    for k in range(8, 58):
        mgr.step(k * DT)
    assert mgr.state("i") == "started"
    assert 58 * DT - 8 * DT < 2.0
    mgr.step(58 * DT)
    assert (mgr.state("i"), host.pos["b"][0], mgr.is_playing("i")) == ("final", 1.0, False)
    assert mgr.get_t("i") == 2.0
    assert TIME_EPS == 1e-9


def test_done_events() -> None:
    """§3 setDoneEvent: thrown on S_final at the end of the step; never for a SoundInterval."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"l": ("l", lerp(0.08, 1.0)), "s": ("s", SoundSpec("beep", 0.04))})
    mgr.start("l", 0.0)
    mgr.start("s", 0.0)
    run(mgr, host, 0.0, 0.12)
    done = [e[:3] for e in host.entries("event") if e[1] == "done"]
    assert done == [("l", "done", pytest.approx(0.08))]
    assert host.entries("stop") == [("beep", pytest.approx(0.04), pytest.approx(0.04))]
