"""Panda3D interval semantics (runner.intervals) against notes/panda3d-semantics.md sections 1-3.

Each test names the notes' section it checks. The frame loop is driven as Panda3D's: an operation at
frame time T (a key handler), then ``step(T)``, ``step(T + dt)``, ... with dt = 0.04 as in the lab.
``tests/unit/test_intervals_panda3d.py`` compares the same machinery with real Panda3D, frame by frame.
"""

from __future__ import annotations

from typing import Any

import pytest

from runner.intervals import (
    TIME_EPS,
    FuncSpec,
    IntervalManager,
    LerpSpec,
    ParallelSpec,
    SequenceSpec,
    SoundSpec,
    WaitSpec,
    compute_delta,
)

DT = 0.04
TOL = 1e-9  # double arithmetic on exact inputs


class Host:
    """A recording IntervalHost: poses as set, and a log of every callback."""

    def __init__(self, **poses: tuple[float, float, float]) -> None:
        self.pos: dict[str, tuple[float, float, float]] = dict(poses)
        self.hpr: dict[str, tuple[float, float, float]] = {}
        self.scale: dict[str, float] = {}
        self.log: list[tuple[Any, ...]] = []
        self.now = 0.0  # the frame being run, to check that `at` is never later
        self.on_actions: dict[str, Any] = {}

    def get_pos(self, body: str) -> tuple[float, float, float]:
        return self.pos.get(body, (0.0, 0.0, 0.0))

    def get_hpr(self, body: str) -> tuple[float, float, float]:
        return self.hpr.get(body, (0.0, 0.0, 0.0))

    def get_scale(self, body: str) -> float:
        return self.scale.get(body, 1.0)

    def set_pos(self, body: str, pos: tuple[float, float, float]) -> None:
        self.pos[body] = pos

    def set_hpr(self, body: str, hpr: tuple[float, float, float]) -> None:
        self.hpr[body] = hpr

    def set_scale(self, body: str, scale: float) -> None:
        self.scale[body] = scale

    def run_actions(self, actions: Any, at: float) -> None:
        assert at <= self.now + TOL
        self.log.append(("func", actions, at, self.now))
        if actions in self.on_actions:
            self.on_actions[actions]()

    def play_sound(self, sound: str, offset: float, volume: float, loop: bool, at: float) -> None:
        assert at <= self.now + TOL
        self.log.append(("play", sound, offset, at, self.now))

    def stop_sound(self, sound: str, at: float) -> None:
        assert at <= self.now + TOL
        self.log.append(("stop", sound, at, self.now))

    def interval_event(self, ival: str, what: str, at: float) -> None:
        self.log.append(("event", ival, what, at, self.now))

    def entries(self, kind: str) -> list[tuple[Any, ...]]:
        return [e[1:] for e in self.log if e[0] == kind]

    def funcs(self) -> list[Any]:
        return [e[0] for e in self.entries("func")]


def run(mgr: IntervalManager, host: Host, t0: float, t1: float, body: str = "b", axis: int = 0) -> list[float]:
    """Step frames t0, t0+dt, ... <= t1 (times k*dt, as the runner computes them); return one coordinate."""
    out = []
    k = round(t0 / DT)
    while k * DT <= t1 + TOL:
        host.now = k * DT
        mgr.step(k * DT)
        out.append(host.get_pos(body)[axis])
        k += 1
    return out


def lerp(duration: float, end: float, body: str = "b", **kw: Any) -> LerpSpec:
    return LerpSpec(body=body, duration=duration, pos=(end, 0.0, 0.0), **kw)


# --- §1 LerpPosInterval ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("blend", "expected"),
    [
        ("noBlend", (0.25, 0.5, 0.75)),
        ("easeIn", (0.0859, 0.3125, 0.6328)),
        ("easeOut", (0.3672, 0.6875, 0.9141)),
        ("easeInOut", (0.1563, 0.5, 0.8438)),
    ],
)
def test_blend_values_at_quarter_points(blend: str, expected: tuple[float, float, float]) -> None:
    """§1 table: the notes give 4 decimals, so 5e-5 is their rounding."""
    for frac, value in zip((0.25, 0.5, 0.75), expected):
        assert compute_delta(frac * 2.0, 2.0, blend) == pytest.approx(value, abs=5e-5)
    assert compute_delta(0.0, 2.0, blend) == 0.0
    assert compute_delta(2.0, 2.0, blend) == 1.0
    assert compute_delta(-1.0, 2.0, blend) == 0.0  # clamped
    assert compute_delta(3.0, 2.0, blend) == 1.0
    assert compute_delta(0.0, 0.0, blend) == 1.0  # duration 0 -> 1.0: the lerp works as a set


def test_unknown_blend_is_refused() -> None:
    """§1: other strings are BT_invalid in Panda3D; here they are refused up front."""
    with pytest.raises(ValueError, match="easeInOut"):
        compute_delta(0.5, 1.0, "smooth")
    with pytest.raises(ValueError, match="blend"):
        LerpSpec(body="b", duration=1.0, blend="ease", pos=(0.0, 0.0, 0.0))


def test_pos_hpr_scale_lerp_together_hpr_without_wrap() -> None:
    """§1: pos, hpr (per component, degrees, no wrap: 0 -> 350 passes 175 at half) and scale."""
    host = Host(b=(0.0, 0.0, 0.0))
    host.hpr["b"] = (0.0, 10.0, 0.0)
    host.scale["b"] = 0.3
    spec = LerpSpec(body="b", duration=1.0, pos=(2.0, 4.0, -6.0), hpr=(350.0, -10.0, 90.0), scale=1.3)
    mgr = IntervalManager(host, {"i": ("i", spec)})
    mgr.start("i", 0.0)
    for k in range(13):  # 0.00 .. 0.48
        mgr.step(k * DT)
    mgr.step(0.5)
    assert host.pos["b"] == pytest.approx((1.0, 2.0, -3.0), abs=TOL)
    assert host.hpr["b"] == pytest.approx((175.0, 0.0, 45.0), abs=TOL)  # not -5 (the short way)
    assert host.scale["b"] == pytest.approx(0.8, abs=TOL)
    mgr.step(1.0)
    assert host.hpr["b"] == (350.0, -10.0, 90.0)
    assert host.scale["b"] == 1.3
    assert mgr.state("i") == "final"


def test_start_value_baked_at_first_step_and_reused() -> None:
    """§1 bakeInStart=1: captured at the first step, not at start(); replays jump back to it."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"i": ("i", lerp(0.2, 10.0))})
    mgr.start("i", 0.0)
    host.pos["b"] = (2.0, 0.0, 0.0)  # [checked] start(), setPos(2,0,0), step -> ran from 2
    assert run(mgr, host, 0.0, 0.2) == pytest.approx([2.0, 3.6, 5.2, 6.8, 8.4, 10.0], abs=1e-12)
    host.pos["b"] = (-7.0, 0.0, 0.0)
    mgr.start("i", 0.4)  # start() on S_final: runs again from the baked start, not from -7
    assert run(mgr, host, 0.4, 0.44) == pytest.approx([2.0, 3.6], abs=1e-12)


def test_given_start_value_is_used() -> None:
    """§1 startPos given: pos = start + d*(end - start) whatever the body's position."""
    host = Host(b=(100.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"i": ("i", lerp(0.2, 10.0, start_pos=(5.0, 0.0, 0.0), blend="easeIn"))})
    mgr.start("i", 0.0)
    got = run(mgr, host, 0.0, 0.2)
    assert got == pytest.approx([5.0 + 5.0 * compute_delta(k * DT, 0.2, "easeIn") for k in range(6)], abs=TOL)


def test_sequence_child_bakes_when_the_sequence_reaches_it() -> None:
    """§1: a Sequence child captures at its priv_initialize; when finished first, at priv_instant."""
    host = Host(b=(0.0, 0.0, 0.0))
    seq = SequenceSpec((WaitSpec(0.2), lerp(0.2, 10.0)))
    mgr = IntervalManager(host, {"s": ("s", seq), "f": ("f", seq)})
    mgr.start("s", 0.0)
    run(mgr, host, 0.0, 0.08)
    host.pos["b"] = (4.0, 0.0, 0.0)  # moved before the child begins
    assert run(mgr, host, 0.12, 0.28) == pytest.approx([4.0, 4.0, 4.0, 5.2, 6.4], abs=1e-12)
    host.pos["b"] = (-1.0, 0.0, 0.0)
    mgr.finish("f", 0.3)  # never stepped: priv_instant bakes -1 and jumps to the end
    assert host.pos["b"] == (10.0, 0.0, 0.0)


# --- §2 Two intervals with the same name -------------------------------------------------------------


def test_same_name_start_finishes_the_playing_one() -> None:
    """§2 C++: the old object jumps to its end state inside the second start() [checked: a at 1.6 -> 10]."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"open": ("door", lerp(2.0, 10.0)), "close": ("door", lerp(2.0, -5.0))})
    mgr.start("open", 0.0)
    run(mgr, host, 0.0, 1.6)
    assert host.pos["b"][0] == pytest.approx(8.0, abs=1e-12)  # a at 1.6
    host.now = 1.6
    mgr.start("close", 1.6)
    assert host.pos["b"][0] == 10.0  # -> 10, inside start(), before any step
    assert mgr.state("open") == "final"
    assert mgr.get_t("open") == 2.0
    assert run(mgr, host, 1.6, 1.64) == pytest.approx([10.0, 10.0 - 15.0 * 0.02], abs=1e-12)
    assert mgr.is_playing("open")  # isPlaying() looks the *name* up: True for the old object
    assert ("event", "open", "taken_over", 1.6, 1.6) in host.log


def test_same_name_start_finishes_even_a_never_stepped_interval() -> None:
    """§2: finish_interval on S_initial is priv_instant: bakes, jumps to the end, no step needed."""
    host = Host(b=(3.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"open": ("door", lerp(2.0, 10.0)), "close": ("door", lerp(2.0, -5.0))})
    mgr.start("open", 0.0)
    mgr.start("close", 0.0)
    assert host.pos["b"][0] == 10.0
    assert run(mgr, host, 0.0, 0.04) == pytest.approx([10.0, 10.0 - 15.0 * 0.02], abs=1e-12)


def test_takeover_runs_python_children_of_a_meta_at_the_next_step() -> None:
    """§2: Funcs (and sounds) of a Sequence finished by a same-name start run in the next step()."""
    host = Host(b=(0.0, 0.0, 0.0))
    close = SequenceSpec((lerp(2.0, 1.0), FuncSpec("slam"), SoundSpec("close", 0.5), FuncSpec("after")))
    mgr = IntervalManager(host, {"close": ("door", close), "open": ("door", lerp(2.0, -1.0))})
    mgr.start("close", 0.0)
    run(mgr, host, 0.0, 1.0)
    host.now = 1.04
    mgr.start("open", 1.04)
    assert host.pos["b"][0] == 1.0  # the C++ child jumped at once
    assert host.funcs() == []  # not inside start()
    mgr.step(1.04)
    assert host.funcs() == ["slam", "after"]  # in order; the skipped sound never plays
    assert host.entries("play") == []
    assert all(e[2] == 1.04 for e in host.entries("func"))


def test_same_name_python_intervals_pause_instead() -> None:
    """§2 Python (Func, SoundInterval): __removeTask interrupts the old one: paused, no jump."""
    host = Host()
    specs = {"s1": ("snd", SoundSpec("hum", 1.0)), "s2": ("snd", SoundSpec("buzz", 1.0))}
    mgr = IntervalManager(host, specs)
    mgr.start("s1", 0.0)
    run(mgr, host, 0.0, 0.2)
    host.now = 0.24
    mgr.start("s2", 0.24)
    assert mgr.state("s1") == "paused"
    assert mgr.get_t("s1") == pytest.approx(0.2, abs=1e-12)  # no jump to 1.0
    assert host.entries("stop") == [("hum", 0.24, 0.24)]  # privInterrupt stops its sound
    assert mgr.is_playing("s1") and mgr.is_playing("s2")


def test_same_name_cpp_and_python_intervals_do_not_interact() -> None:
    """§2: a Python interval's task and a C++ interval's manager entry are separate name spaces."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"l": ("x", lerp(0.2, 1.0)), "f": ("x", FuncSpec("f"))})
    mgr.start("l", 0.0)
    mgr.start("f", 0.0)
    run(mgr, host, 0.0, 0.08)
    assert host.funcs() == ["f"]
    assert mgr.state("l") == "started" and host.pos["b"][0] == pytest.approx(0.4, abs=1e-12)


@pytest.mark.parametrize(("first", "second"), [("aaa", "zzz"), ("zzz", "aaa")])
def test_intervals_step_in_name_order(first: str, second: str) -> None:
    """§2: of two names driving one property, the later-sorting name wins each frame."""
    host = Host(b=(0.0, 0.0, 0.0))
    mgr = IntervalManager(host, {"up": (first, lerp(1.0, 10.0)), "down": (second, lerp(1.0, -10.0))})
    mgr.start("down", 0.0)
    mgr.start("up", 0.0)
    sign = 1.0 if first > second else -1.0
    assert run(mgr, host, 0.0, 0.2) == pytest.approx([sign * 10.0 * k * DT for k in range(6)], abs=1e-12)


def test_python_intervals_run_before_cpp_ones() -> None:
    """§0/§2: `<name>-play` tasks (sort 0) run before ivalLoop (sort 20) in a frame."""
    host = Host(b=(0.0, 0.0, 0.0))
    seen: list[float] = []
    host.on_actions["look"] = lambda: seen.append(host.pos["b"][0])
    mgr = IntervalManager(host, {"l": ("a", lerp(0.4, 4.0)), "f": ("z", FuncSpec("look"))})
    mgr.start("l", 0.0)
    run(mgr, host, 0.0, 0.08)
    host.now = 0.12
    mgr.start("f", 0.12)
    run(mgr, host, 0.12, 0.12)
    assert seen == [pytest.approx(0.8, abs=1e-12)]  # the frame-0.08 pose: the lerp had not stepped yet
    assert host.pos["b"][0] == pytest.approx(1.2, abs=1e-12)


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


def test_specs_refuse_bad_values() -> None:
    with pytest.raises(ValueError, match="duration"):
        WaitSpec(-1.0)
    with pytest.raises(ValueError, match="at least one"):
        LerpSpec(body="b", duration=1.0)
    with pytest.raises(ValueError, match="start_pos"):
        LerpSpec(body="b", duration=1.0, hpr=(0.0, 0.0, 0.0), start_pos=(1.0, 0.0, 0.0))
    mgr = IntervalManager(Host(), {"i": ("i", lerp(1.0, 1.0))})
    with pytest.raises(ValueError, match="rate"):
        mgr.start("i", 0.0, rate=0.0)
    with pytest.raises(KeyError, match="Unknown interval"):
        mgr.start("nope", 0.0)


def test_public_names_are_sorted_and_complete() -> None:
    import runner.intervals as ivals

    assert ivals.__all__ == sorted(ivals.__all__)
    assert all(hasattr(ivals, name) for name in ivals.__all__)
