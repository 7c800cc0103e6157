"""Play a conformance scenario's timeline on real Panda3D, headless: run as ``python -m`` (a subprocess).

Input (stdin, JSON): a list of ``{"path": scenario file, "variant": name or null, "listen": [event names]}``,
played one after the other in one ShowBase, each in its own subtree with its own clock origin. The
scenario is read with the runner's loader (data only) and rebuilt from Panda3D's own classes: a NodePath
per body, LerpPos/Hpr/Scale intervals, Sequence, Parallel, Wait, Func, SoundInterval (with its explicit
duration), CollisionSphere / CollisionPolygon / CollisionBox solids in CollisionNodes, a
CollisionTraverser as ``base.cTrav`` and a CollisionHandlerEvent with the scenario's in / again / out
patterns. ``ShowBase(windowType='none')``, a non-real-time ``ClockObject`` at the scenario's dt (frame k
of job n has frame time (n + 1)*T0 + k*dt), frames advanced by
``taskMgr.step()``. A timed input due at step k is queued before frame k, so the eventManager delivers it
in that frame, as the runner does. Handlers run the scenario's interval actions (start, pause, resume,
finish, loop) and ``send``; state actions have no Panda3D counterpart and are skipped.

Sounds come from the Null audio manager (``audio-library-name null``): ``loader.loadSfx`` gives a
NullAudioSound of length 0, which a SoundInterval would never start. Each is wrapped so that ``length()``
reports the WAV file's length, as a real audio manager would, and play/stop calls are logged.

Output (stdout, JSON): per job ``{"frames": [{"t": k*dt, "poses": {body: [x, y, z, h, p, r, scale]}}],
"events": [[k*dt, name]], "sounds": [[k*dt, name, "start" | "stop"]]}``; times are relative to the job's
first frame.
"""

from __future__ import annotations

import json
import math
import os
import sys
import wave
from pathlib import Path
from typing import Any

T0 = 1024.0  # job n's first frame is at (n + 1)*T0: exact in binary, so is every frame time for dt = 1/32


def _inputs(model: Any, dt: float, steps: int) -> dict[int, list[str]]:
    """Timed inputs by frame: an input at t is due at the first step whose time is >= t (docs/language.md)."""
    out: dict[int, list[tuple[float, str]]] = {}
    for item in model.inputs:
        times = (
            [item.at] if item.repeat is None else [item.at + k * item.repeat.every for k in range(item.repeat.count)]
        )
        for t in times:
            k = max(0, math.ceil(t / dt - 1e-9))
            if k < steps:
                out.setdefault(k, []).append((t, item.event))
    return {k: [e for _, e in sorted(v, key=lambda x: x[0])] for k, v in out.items()}


class _LoggedSound:
    """A NullAudioSound that reports the WAV file's length and logs play() and stop()."""

    def __init__(self, inner: Any, name: str, length: float, log: list, clock: Any, t0: float) -> None:
        self._inner, self._name, self._length, self._log, self._clock, self._t0 = inner, name, length, log, clock, t0
        self._playing = False

    def length(self) -> float:
        return self._length

    def status(self) -> int:
        return 2 if self._playing else 1

    def play(self) -> None:
        self._playing = True
        self._log.append([self._clock.getFrameTime() - self._t0, self._name, "start"])
        self._inner.play()

    def stop(self) -> None:
        if self._playing:
            self._log.append([self._clock.getFrameTime() - self._t0, self._name, "stop"])
        self._playing = False
        self._inner.stop()

    def __getattr__(self, attr: str) -> Any:
        return getattr(self._inner, attr)


def main() -> None:
    os.environ.setdefault("ALSOFT_DRIVERS", "null")
    from panda3d.core import ClockObject, EventQueue, loadPrcFileData

    loadPrcFileData("", "window-type none\naudio-library-name null\nnotify-level warning\n")
    from direct.interval.IntervalManager import ivalMgr
    from direct.showbase.ShowBase import ShowBase

    base = ShowBase(windowType="none")
    clock = ClockObject.getGlobalClock()
    clock.setMode(ClockObject.MNonRealTime)
    out = []
    for n, job in enumerate(json.load(sys.stdin)):
        out.append(play(base, clock, job, (n + 1) * T0))
        ivalMgr.finishIntervalsMatching("*")  # leftovers of this job (their events are no longer listened to)
        base.taskMgr.removeTasksMatching("*-play")
        EventQueue.getGlobalEventQueue().clear()
    json.dump(out, sys.stdout)


def play(base: Any, clock: Any, job: dict[str, Any], t0: float) -> dict[str, Any]:  # noqa: C901 - one scene
    """Build one scenario's scene under its own node and play its timeline from frame time ``t0``."""
    from direct.interval import IntervalGlobal as IG
    from direct.showbase.DirectObject import DirectObject
    from panda3d.core import (
        CollisionBox,
        CollisionHandlerEvent,
        CollisionNode,
        CollisionPolygon,
        CollisionSphere,
        CollisionTraverser,
        Event,
        EventQueue,
        Point3,
    )

    from runner.language.load import load_scenario

    model = load_scenario(Path(job["path"]), job["variant"]).model
    prefix = f"job{int(t0 / T0)}-"  # interval names of different jobs never meet
    dt = model.world.dt
    steps = max(1, int(math.floor(model.world.duration / dt + 0.5)))
    clock.setFrameRate(1.0 / dt)
    events: list[list] = []
    sound_log: list[list] = []
    root = base.render.attachNewNode(prefix)
    nodes = {}
    for name, body in model.bodies.items():
        node = root.attachNewNode(name)
        node.setPos(*body.pos)
        if body.hpr is not None:
            node.setHpr(*body.hpr)
        elif body.quat is not None:
            from panda3d.core import Quat

            node.setQuat(Quat(*body.quat))
        node.setScale(body.scale)
        nodes[name] = node
    folder = Path(job["path"]).parent
    sounds = {}
    for name, rel in model.sounds.items():
        with wave.open(str(folder / rel), "rb") as w:
            length = w.getnframes() / w.getframerate()
        sounds[name] = _LoggedSound(base.loader.loadSfx(str(folder / rel)), name, length, sound_log, clock, t0)

    ivals: dict[str, Any] = {}

    def run_actions(actions: Any) -> None:
        for action in actions:
            kind = type(action).__name__
            if kind in ("StartAction", "PauseAction", "ResumeAction", "FinishAction", "LoopAction"):
                verb = kind.removesuffix("Action").lower()
                getattr(ivals[getattr(action, verb)], verb)()
            elif kind == "SendAction":
                base.messenger.send(action.send)
            elif kind in ("SetAction", "CalcAction", "LogAction"):
                continue  # runner state: nothing to do in Panda3D
            else:
                raise NotImplementedError(f"action {kind} is not played on Panda3D by this test")

    def build(step: Any, name: str | None = None) -> Any:
        kw = {} if name is None else {"name": name}
        if step.lerp is not None:
            s = step.lerp
            node, d, blend = nodes[s.body], s.duration, s.blend
            if s.pos is not None and s.hpr is None and s.scale is None:
                return IG.LerpPosInterval(node, d, s.pos, startPos=s.start_pos, blendType=blend, **kw)
            if s.hpr is not None and s.pos is None and s.scale is None:
                return IG.LerpHprInterval(node, d, s.hpr, startHpr=s.start_hpr, blendType=blend, **kw)
            if s.scale is not None and s.pos is None and s.hpr is None:
                return IG.LerpScaleInterval(node, d, s.scale, startScale=s.start_scale, blendType=blend, **kw)
            return IG.LerpPosHprScaleInterval(
                node, d, s.pos or node.getPos(), s.hpr or node.getHpr(), s.scale or node.getScale(),
                startPos=s.start_pos, startHpr=s.start_hpr, startScale=s.start_scale, blendType=blend, **kw,
            )  # fmt: skip
        if step.wait is not None:
            return IG.Wait(step.wait)
        if step.func is not None:
            return IG.Func(run_actions, step.func, **kw)
        if step.sound is not None:
            spec = step.sound if not isinstance(step.sound, str) else None
            sound = sounds[step.sound if spec is None else spec.sound]
            return IG.SoundInterval(
                sound,
                loop=int(spec.loop) if spec else 0,
                duration=(spec.duration or 0.0) if spec else 0.0,
                volume=spec.volume if spec else 1.0,
                startTime=spec.start_time if spec else 0.0,
                **kw,
            )
        if step.interval is not None:
            return build(model.intervals[step.interval])
        children = [build(c) for c in (step.sequence if step.sequence is not None else step.parallel)]
        if step.duration is not None:
            kw["duration"] = step.duration
        return (IG.Sequence if step.sequence is not None else IG.Parallel)(*children, **kw)

    for ival, definition in model.intervals.items():
        ivals[ival] = build(definition, prefix + (definition.name or ival))

    c = model.collisions
    if c.nodes:
        handler = CollisionHandlerEvent()
        for pattern in c.in_:
            handler.addInPattern(pattern)
        for pattern in c.again:
            handler.addAgainPattern(pattern)
        for pattern in c.out:
            handler.addOutPattern(pattern)
        base.cTrav = CollisionTraverser()
        for name, cn in c.nodes.items():
            cnode = CollisionNode(name)
            for solid in cn.all_solids():
                if solid.sphere is not None:
                    cnode.addSolid(CollisionSphere(Point3(*solid.sphere.center), solid.sphere.radius))
                elif solid.polygon is not None:
                    cnode.addSolid(CollisionPolygon(*(Point3(*v) for v in solid.polygon)))
                else:
                    half = [s / 2 for s in solid.box.size]
                    cnode.addSolid(CollisionBox(Point3(*solid.box.center), *half))
            path = nodes[cn.body].attachNewNode(cnode)
            if name in c.from_:
                base.cTrav.addCollider(path, handler)
    else:
        base.cTrav = 0  # ShowBase's "no traverser"

    listener = DirectObject()
    names = set(model.on) | {e for v in _inputs(model, dt, steps).values() for e in v}

    def deliver(name: str, *args: Any) -> None:
        events.append([clock.getFrameTime() - t0, name])
        run_actions(model.on.get(name, []))

    for name in sorted(names | set(job.get("listen", []))):
        listener.accept(name, deliver, [name])

    inputs = _inputs(model, dt, steps)
    clock.setFrameTime(t0)
    frames = []
    for k in range(steps + 1):
        for event in inputs.get(k, []):
            EventQueue.getGlobalEventQueue().queueEvent(Event(event))
        t = clock.getFrameTime() - t0  # the clock ticks at the end of the frame (igLoop)
        base.taskMgr.step()
        poses = {n: [*nd.getPos(), *nd.getHpr(), nd.getScale()[0]] for n, nd in nodes.items()}
        frames.append({"t": t, "poses": poses})
    listener.ignoreAll()
    root.removeNode()
    return {"frames": frames, "events": events, "sounds": sound_log}


if __name__ == "__main__":
    main()
