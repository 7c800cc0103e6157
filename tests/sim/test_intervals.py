"""Panda3D interval semantics (runner.sim.intervals) against notes/panda3d-semantics.md sections 1-2.

Each test names the notes' section it checks; section 3 (the control API) is in
test_intervals_control.py. The frame loop is driven as Panda3D's: an operation at frame time T (a key
handler), then ``step(T)``, ``step(T + dt)``, ... with dt = 0.04 as in the lab.
``tests/sim/test_intervals_panda3d.py`` compares the same machinery with real Panda3D, frame by frame.
"""

from __future__ import annotations

from typing import Any

import pytest

from runner.sim.intervals import (
    FuncSpec,
    IntervalManager,
    LerpSpec,
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
    for frac, value in zip((0.25, 0.5, 0.75), expected, strict=True):
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
    import runner.sim.intervals as ivals

    assert ivals.__all__ == sorted(ivals.__all__)
    assert all(hasattr(ivals, name) for name in ivals.__all__)
