"""runner.sim.intervals against real Panda3D 1.10, frame by frame.

Each case is a set of intervals (id -> Panda3D name, spec) and operations run by a key handler at given
frames (Funcs may run operations too). Panda3D runs them in a subprocess (this module run with ``-m``):
``ShowBase(windowType='none')``, a non-real-time clock with dt = 1/32 s moved to 1024*(case+1) s so
that every frame time is an exact binary fraction, handlers fed through the global event queue, sounds
through a patched ``sfxPlayer.playSfx``. runner.sim.intervals runs the same case in-process with
``now = k*dt``: operations, then ``step(now)``. After every frame both sides report each body's pos,
hpr and scale (Panda3D works in float32, hence 2e-4), each interval's state, isPlaying() and getT();
the ordered logs of Func calls, sound plays/stops and done events must match too.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from .test_intervals_panda3d_cases import CASES, DT

ROOT = Path(__file__).resolve().parents[2]
STATES = ("initial", "started", "paused", "final")


def _r(x: float) -> float:
    return round(float(x), 5)


# --- the runner.sim.intervals side ----------------------------------------------------------------------------


def _spec(raw: dict) -> Any:
    from runner.sim.intervals import FuncSpec, LerpSpec, ParallelSpec, SequenceSpec, SoundSpec, WaitSpec

    if "lerp" in raw:
        return LerpSpec(**{k: tuple(v) if isinstance(v, list) else v for k, v in raw["lerp"].items()})
    if "wait" in raw:
        return WaitSpec(raw["wait"])
    if "func" in raw:
        return FuncSpec(tuple(tuple(op) for op in raw["func"]))
    if "sound" in raw:
        return SoundSpec(**raw["sound"])
    children = tuple(_spec(c) for c in raw.get("seq", raw.get("par", [])))
    return (SequenceSpec if "seq" in raw else ParallelSpec)(children, raw.get("duration"))


def run_model(sc: dict) -> tuple[list, list]:
    from runner.sim.intervals import IntervalManager

    log: list[list] = []
    frame = [0]
    poses = {
        b: [
            tuple(map(float, v.get("pos", (0, 0, 0)))),
            tuple(map(float, v.get("hpr", (0, 0, 0)))),
            float(v.get("scale", 1)),
        ]
        for b, v in sc["bodies"].items()
    }

    class Host:
        def get_pos(self, b: str) -> Any:
            return poses[b][0]

        def get_hpr(self, b: str) -> Any:
            return poses[b][1]

        def get_scale(self, b: str) -> Any:
            return poses[b][2]

        def set_pos(self, b: str, v: Any) -> None:
            poses[b][0] = v

        def set_hpr(self, b: str, v: Any) -> None:
            poses[b][1] = v

        def set_scale(self, b: str, v: float) -> None:
            poses[b][2] = v

        def run_actions(self, ops: Any, at: float) -> None:
            run_ops(ops, frame[0] * DT)

        def play_sound(self, s: str, offset: float, volume: float, loop: bool, at: float) -> None:
            log.append(["play", s, _r(offset), loop, _r(volume), frame[0]])

        def stop_sound(self, s: str, at: float) -> None:
            log.append(["stop", s, frame[0]])

        def interval_event(self, ival: str, what: str, at: float) -> None:
            if what == "done":
                log.append(["done", ival, frame[0]])

    mgr = IntervalManager(Host(), {i: (name, _spec(raw)) for i, (name, raw) in sc["intervals"].items()})

    def run_ops(ops: Any, now: float) -> None:
        for kind, *args in ops:
            if kind == "log":
                log.append(["func", args[0], frame[0]])
            else:
                getattr(mgr, kind)(args[0], now, *args[1:])

    frames = []
    for k in range(sc["frames"]):
        frame[0] = k
        run_ops(sc["ops"].get(str(k), []), k * DT)
        mgr.step(k * DT)
        pose = {b: [_r(v) for v in (*p[0], *p[1], p[2])] for b, p in poses.items()}
        state = {i: [STATES.index(mgr.state(i)), mgr.is_playing(i), _r(mgr.get_t(i))] for i in sc["intervals"]}
        frames.append([pose, state])
    return frames, log


# --- the Panda3D side (a subprocess) ------------------------------------------------------------------------


def _panda_main() -> None:  # pragma: no cover - runs in the subprocess
    os.environ.setdefault("ALSOFT_DRIVERS", "null")
    from panda3d.core import ClockObject, Event, EventQueue, loadPrcFileData

    loadPrcFileData("", "window-type none\naudio-library-name null\nnotify-level warning\nnotify-level-device fatal\n")
    from direct.interval import IntervalGlobal as IG
    from direct.interval.IntervalManager import ivalMgr
    from direct.showbase.ShowBase import ShowBase

    base = ShowBase(windowType="none")
    clock = ClockObject.getGlobalClock()
    clock.setMode(ClockObject.MNonRealTime)
    clock.setFrameRate(1.0 / DT)
    results = {}
    for n, (name, sc) in enumerate(json.load(sys.stdin).items()):
        results[name] = json.loads(json.dumps(_panda_case(base, IG, clock, Event, EventQueue, sc, n)))
        ivalMgr.finishIntervalsMatching("*")  # (after the snapshot: this runs leftover Funcs)
        base.taskMgr.removeTasksMatching("*-play")
    json.dump(results, sys.stdout)


def _panda_case(base: Any, IG: Any, clock: Any, Event: Any, EventQueue: Any, sc: dict, n: int) -> Any:
    log: list[list] = []
    frame = [0]
    prefix = f"c{n:02d}-"
    nodes = {}
    for b, p in sc["bodies"].items():
        node = base.render.attachNewNode(b)
        node.setPos(*p.get("pos", (0, 0, 0)))
        node.setHpr(*p.get("hpr", (0, 0, 0)))
        node.setScale(p.get("scale", 1.0))
        nodes[b] = node

    class FakeSound:
        def __init__(self, name: str, length: float) -> None:
            self.name, self._length, self.playing = name, length, False

        def length(self) -> float:
            return self._length

        def setVolume(self, volume: float) -> None:
            pass

        def stop(self) -> None:
            if self.playing:  # a stop of a silent sound changes nothing: not logged
                log.append(["stop", self.name, frame[0]])
            self.playing = False

    def play_sfx(
        sfx: Any, looping: int = 0, interrupt: int = 1, volume: Any = None, time: float = 0.0, *a: Any, **k: Any
    ) -> None:
        sfx.playing = True
        log.append(["play", sfx.name, _r(time), bool(looping), _r(volume), frame[0]])

    base.sfxPlayer.playSfx = play_sfx
    sounds: dict[str, FakeSound] = {}
    ivals: dict[str, Any] = {}

    def run_ops(ops: Any) -> None:
        for kind, *args in ops:
            if kind == "log":
                log.append(["func", args[0], frame[0]])
            else:
                getattr(ivals[args[0]], kind)(*args[1:])

    def build(raw: dict, name: str | None = None) -> Any:
        kw = {} if name is None else {"name": prefix + name}
        if "lerp" in raw:
            s = {k: tuple(v) if isinstance(v, list) else v for k, v in raw["lerp"].items()}
            node, d, blend = nodes[s["body"]], s["duration"], s.get("blend", "noBlend")
            has = tuple(k for k in ("pos", "hpr", "scale") if s.get(k) is not None)
            start = {k: s.get("start_" + k) for k in has}
            if has == ("pos",):
                return IG.LerpPosInterval(node, d, s["pos"], startPos=start["pos"], blendType=blend, **kw)
            if has == ("hpr",):
                return IG.LerpHprInterval(node, d, s["hpr"], startHpr=start["hpr"], blendType=blend, **kw)
            if has == ("scale",):
                return IG.LerpScaleInterval(node, d, s["scale"], startScale=start["scale"], blendType=blend, **kw)
            if has == ("pos", "hpr"):
                return IG.LerpPosHprInterval(
                    node, d, s["pos"], s["hpr"], startPos=start["pos"], startHpr=start["hpr"], blendType=blend, **kw
                )
            if has == ("hpr", "scale"):
                return IG.LerpHprScaleInterval(
                    node,
                    d,
                    s["hpr"],
                    s["scale"],
                    startHpr=start["hpr"],
                    startScale=start["scale"],
                    blendType=blend,
                    **kw,
                )
            return IG.LerpPosHprScaleInterval(
                node, d, s["pos"], s["hpr"], s["scale"], startPos=start["pos"], startHpr=start["hpr"],
                startScale=start["scale"], blendType=blend, **kw,
            )  # fmt: skip
        if "wait" in raw:
            return IG.Wait(raw["wait"])
        if "func" in raw:
            return IG.Func(run_ops, raw["func"], **kw)
        if "sound" in raw:
            s = raw["sound"]
            length = s.get("length", s.get("start_time", 0.0) + s["duration"])
            sound = sounds.setdefault(s["sound"], FakeSound(s["sound"], length))
            return IG.SoundInterval(
                sound, loop=int(s.get("loop", False)), duration=s["duration"], volume=s.get("volume", 1.0),
                startTime=s.get("start_time", 0.0), **kw,
            )  # fmt: skip
        children = [build(c) for c in raw.get("seq", raw.get("par", []))]
        if raw.get("duration") is not None:
            kw["duration"] = raw["duration"]
        return (IG.Sequence if "seq" in raw else IG.Parallel)(*children, **kw)

    for ival, (name, raw) in sc["intervals"].items():
        ivals[ival] = build(raw, name)
        ivals[ival].setDoneEvent(f"{prefix}done-{ival}")
        base.accept(f"{prefix}done-{ival}", lambda i=ival: log.append(["done", i, frame[0]]))
    for k, ops in sc["ops"].items():
        base.accept(f"{prefix}ops-{k}", run_ops, [ops])
    clock.setFrameTime(1024.0 * (n + 1))  # exact frame times; later than every task already added
    frames = []
    for k in range(sc["frames"]):
        frame[0] = k
        if str(k) in sc["ops"]:
            EventQueue.getGlobalEventQueue().queueEvent(Event(f"{prefix}ops-{k}"))
        base.taskMgr.step()
        pose = {b: [_r(v) for v in (*nd.getPos(), *nd.getHpr(), nd.getScale()[0])] for b, nd in nodes.items()}
        state = {i: [int(iv.getState()), bool(iv.isPlaying()), _r(iv.getT())] for i, iv in ivals.items()}
        frames.append([pose, state])
    return frames, log


# --- the comparison ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def panda() -> dict:
    pytest.importorskip("panda3d", reason="Panda3D (extra `ode`) is the reference these cases are checked against")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "ALSOFT_DRIVERS": "null"}
    proc = subprocess.run(
        [sys.executable, "-m", "tests.sim.test_intervals_panda3d"],
        input=json.dumps(CASES),
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    return json.loads(proc.stdout)


def _close(a: Any, b: Any) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    if isinstance(a, float) or isinstance(b, float):
        return abs(a - b) <= 2e-4  # Panda3D's float32 positions and angles
    return a == b


@pytest.mark.parametrize("name", list(CASES))
def test_matches_panda3d_frame_by_frame(panda: dict, name: str) -> None:
    ref_frames, ref_log = panda[name]
    frames, log = run_model(CASES[name])
    assert len(frames) == len(ref_frames) == CASES[name]["frames"]
    for k, (ours, ref) in enumerate(zip(frames, ref_frames, strict=True)):
        assert _close(ours, ref), f"frame {k}:\n ours  {ours}\n panda {ref}"
    assert _close(log, ref_log), f"\n ours  {log}\n panda {ref_log}"


if __name__ == "__main__":
    _panda_main()
