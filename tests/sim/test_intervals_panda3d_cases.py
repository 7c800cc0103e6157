"""The cases test_intervals_panda3d.py plays on Panda3D and on runner.sim.intervals (data only, no tests).

A case: bodies with their initial pose, intervals (id -> [Panda3D name, spec]) and the operations a key
handler runs at given frames (["start", id, startT?, endT?, rate?], ["pause", id], ["resume", id, t?],
["finish", id], ["loop", id]); a Func's spec is a list of such operations plus ["log", label].
"""

from __future__ import annotations

from typing import Any

DT = 1.0 / 32.0  # seconds per frame: exact in binary, so both clocks agree to the last bit


def L(body: str, d: float, **kw: Any) -> dict:
    return {"lerp": {"body": body, "duration": d, **kw}}


def F(*items: Any) -> dict:
    return {"func": [["log", x] if isinstance(x, str) else list(x) for x in items]}


def S(sound: str, d: float, **kw: Any) -> dict:
    return {"sound": {"sound": sound, "duration": d, **kw}}


def SEQ(*c: dict, **kw: Any) -> dict:
    return {"seq": list(c), **kw}


def PAR(*c: dict, **kw: Any) -> dict:
    return {"par": list(c), **kw}


def W(d: float) -> dict:
    return {"wait": d}


def case(intervals: dict, ops: dict, frames: int = 40, bodies: dict | None = None) -> dict:
    bodies = bodies or {"a": {"pos": [0, 0, 0]}, "b": {"pos": [5, 0, 0]}}
    return {"frames": frames, "bodies": bodies, "intervals": intervals, "ops": {str(k): v for k, v in ops.items()}}


SEQ7 = SEQ(F("f0"), L("a", 0.2, pos=[1, 0, 0]), F("f1"), W(0.1), F("f2"), L("a", 0.2, pos=[2, 0, 0]), F("f3"))
CASES = {
    "sequence_timing": case({"s": ["seq", SEQ7]}, {2: [["start", "s"]]}),
    "takeover_lerp": case(
        {"o": ["door", L("a", 2.0, pos=[10, 0, 0], blend="easeInOut")], "c": ["door", L("a", 2.0, pos=[-5, 0, 0])]},
        {1: [["start", "o"]], 30: [["start", "c"]]},
        frames=50,
    ),
    "takeover_never_stepped": case(
        {"o": ["door", L("a", 2.0, pos=[10, 0, 0])], "c": ["door", L("a", 2.0, pos=[-5, 0, 0])]},
        {1: [["start", "o"], ["start", "c"]], 5: [["start", "o"]]},
        frames=12,
    ),
    "takeover_meta_python_children": case(
        {
            "o": ["door", L("a", 1.0, pos=[10, 0, 0])],
            "c": ["door", SEQ(F("c0"), L("a", 1.0, pos=[-5, 0, 0]), F("c1"), S("close", 0.5), F("c2"))],
        },
        {1: [["start", "c"]], 10: [["start", "o"]], 20: [["start", "c"]], 40: [["start", "o"]]},
        frames=70,
    ),
    "python_same_name": case(
        {"f": ["ff", F("f")], "g": ["ff", F("g")], "s1": ["snd", S("s1", 1.0)], "s2": ["snd", S("s2", 1.0)]},
        {
            1: [["start", "f"], ["start", "g"]],
            3: [["start", "f"]],
            4: [["start", "f"], ["start", "f"]],  # the second start interrupts the first: f is not called
            6: [["start", "f"]],
            8: [["start", "s1"]],
            12: [["start", "s2"]],
            14: [["pause", "s1"]],  # removes the task named snd-play: s2's
            16: [["resume", "s1"]],
            20: [["finish", "s1"]],
        },
        frames=30,
    ),
    "pause_resume_sound_child": case(
        {
            "s": [
                "seq",
                SEQ(L("a", 0.5, pos=[1, 0, 0]), PAR(S("snd", 0.6, start_time=0.05), L("b", 0.3, pos=[0, 1, 0]))),
            ]
        },
        {1: [["start", "s"]], 20: [["pause", "s"]], 25: [["resume", "s"]], 30: [["pause", "s"]], 33: [["resume", "s"]]},
        frames=60,
    ),
    "finish_runs_funcs": case(
        {"s": ["seq", SEQ7]},
        {1: [["start", "s"]], 4: [["finish", "s"]], 8: [["finish", "s"]], 10: [["start", "s"]], 12: [["pause", "s"]]},
        frames=20,
    ),
    "restart_rewinds": case(
        {
            "s": ["seq", SEQ(F("f0"), L("a", 0.2, pos=[1, 0, 0]), F("f1"), L("a", 0.2, pos=[2, 0, 0]), F("f2"))],
            "l": ["lerp", L("b", 0.3, pos=[9, 9, 9])],
        },
        {
            1: [["start", "s"], ["start", "l"]],
            10: [["start", "s"], ["start", "l"]],
            30: [["start", "s"], ["start", "l"]],
        },
        frames=45,
    ),
    "loops": case(
        {
            "l": ["lerp", L("a", 0.25, pos=[1, 0, 0], start_pos=[0, 0, 0])],
            "s": ["seq", SEQ(F("x"), L("b", 0.125, pos=[1, 1, 1]), F("y"))],
        },
        {1: [["loop", "l"], ["loop", "s"]], 30: [["pause", "l"]], 33: [["resume", "l"]], 38: [["finish", "l"]]},
        frames=45,
    ),
    "parallel_holds": case(
        {"p": ["par", PAR(L("a", 0.5, pos=[1, 0, 0]), L("b", 0.25, hpr=[350, 0, 0]), SEQ(W(0.1), F("mid")))]},
        {1: [["start", "p"]]},
        frames=25,
    ),
    "name_order": case(
        {"z": ["zzz", L("a", 0.5, pos=[1, 0, 0])], "y": ["aaa", L("a", 0.5, pos=[0, 1, 0])]},
        {1: [["start", "z"], ["start", "y"]]},
        frames=25,
    ),
    "skipped_in_one_frame": case(
        {
            "s": [
                "seq",
                SEQ(L("a", 0.01, pos=[3, 0, 0]), S("short", 0.01, length=1.0), F("after"), L("b", 0.3, scale=2.0)),
            ]
        },
        {1: [["start", "s"]]},
        frames=15,
    ),
    "starts_from_funcs": case(
        {
            "s": ["seq", SEQ(F("s0", ["start", "l"], ["start", "g"]), L("a", 0.1, pos=[1, 0, 0]))],
            "l": ["lerp", L("b", 0.25, pos=[0, 0, 1])],
            "g": ["fg", F("g", ["start", "h"])],
            "h": ["fh", F("h", ["start", "l2"])],
            "l2": ["lerp2", L("a", 0.25, hpr=[90, 0, 0])],
        },
        {1: [["start", "s"]], 10: [["start", "g"]]},
        frames=25,
    ),
    "pause_by_name": case(
        {"o": ["door", L("a", 1.0, pos=[10, 0, 0])], "c": ["door", L("a", 1.0, pos=[-5, 0, 0])]},
        {1: [["start", "o"]], 5: [["start", "c"]], 8: [["pause", "o"]], 12: [["resume", "c"]], 15: [["finish", "o"]]},
        frames=25,
    ),
    "ranges_and_rates": case(
        {
            "l": ["lerp", L("a", 1.0, pos=[1, 0, 0], start_pos=[0, 0, 0])],
            "s": ["seq", SEQ(F("f0"), L("b", 0.5, pos=[1, 0, 0]), F("f1"), L("b", 0.5, pos=[2, 0, 0]), F("f2"))],
        },
        {
            1: [["start", "l", 0.25, 0.75, 2.0], ["start", "s", 0.0, -1, -1.0]],
            20: [["start", "s", 0.3, 0.9, 1.0]],
            40: [["resume", "l", 0.5]],
        },
        frames=70,
    ),
    "phony_durations": case(
        {
            "s": [
                "seq",
                SEQ(
                    PAR(L("a", 0.5, pos=[1, 0, 0]), duration=0.2),
                    F("p"),
                    SEQ(L("b", 0.3, pos=[0, 0, 3]), duration=0.05),
                    F("q"),
                    duration=0.3,
                ),
            ]
        },
        {1: [["start", "s"]]},
        frames=30,
    ),
    "looping_sounds": case(
        {"s": ["snd", S("hum", 0.25, loop=True)], "q": ["seq", SEQ(S("beep", 0.1), W(0.05))]},
        {1: [["loop", "s"], ["loop", "q"]], 20: [["finish", "s"]], 22: [["pause", "q"]]},
        frames=30,
    ),
    "hpr_and_scale": case(
        {
            "l": ["l", L("a", 0.5, hpr=[0, 350, -20], scale=3.0, blend="easeIn")],
            "m": ["m", L("b", 0.5, pos=[1, 2, 3], hpr=[10, 20, 30], scale=0.5, blend="easeOut", start_scale=2.0)],
        },
        {1: [["start", "l"], ["start", "m"]]},
        frames=25,
        bodies={"a": {"hpr": [10, 0, 0], "scale": 0.3}, "b": {"pos": [1, 1, 1]}},
    ),
    "zero_durations": case(
        {"l": ["lerp", L("a", 0.0, pos=[4, 4, 4])], "w": ["Wait", W(0.0)], "e": ["seq", SEQ()], "w2": ["Wait", W(0.1)]},
        {
            1: [["start", "l"], ["start", "w"], ["start", "e"]],
            3: [["start", "w2"]],
            4: [["start", "w"]],
            6: [["finish", "l"]],
        },
        frames=10,
    ),
    "removal_order": case(
        {
            "A": ["aaa", SEQ(W(3 / 32), F("a1"))],
            "B": ["bbb", SEQ(L("a", 1.0, pos=[1, 0, 0]), F("b1"))],
            "C": ["bbb", SEQ(F("c0"), L("b", 0.5, pos=[0, 0, 0]))],
        },
        {1: [["start", "A"], ["start", "B"]], 4: [["start", "C"]]},  # B's Func, then A's, then C's
        frames=10,
    ),
    "reverse_sweeps": case(
        {
            "s": [
                "seq",
                SEQ(
                    F("f0"),
                    PAR(L("a", 0.2, pos=[1, 0, 0]), L("b", 0.3, pos=[0, 1, 0])),
                    F("f1"),
                    L("a", 0.1, hpr=[90, 0, 0]),
                    F("f2"),
                ),
            ]
        },
        {1: [["start", "s"]], 18: [["start", "s"]], 20: [["start", "s", 0.0, -1, -2.0]], 40: [["finish", "s"]]},
        frames=45,
    ),
}
