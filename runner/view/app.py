"""``scenario view``: a scenario live in the window (and ``--record``), or traces replayed.

:func:`view_scenario` checks everything that can be checked before the window opens (the scenario, the
backend, where ``--record`` will write, the display), opens the window on the scene of the compiled
world, runs the case through :func:`runner.sim.run.run_loaded` with :class:`runner.view.live.LiveRun` as
its driver (so the trace is the one ``scenario run`` writes), keeps the window on the end until it is
closed, then writes the recorded variant. :func:`view_traces` replays traces.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from backends.registry import engine_version
from runner.compile.program import build_program
from runner.language.load import LoadedScenario
from runner.sim.run import run_loaded, solid_visuals
from runner.sim.session import RunResult
from runner.trace.encoder import dumps
from runner.trace.foxglove import body_spec_record
from runner.view.display import ViewUnavailable, display_problem
from runner.view.hud import Hud
from runner.view.keys import RESERVED, named_events
from runner.view.record import RecordPlan, plan_record, write_record
from runner.view.script import ScriptEntry

__all__ = ["LiveOutcome", "view_scenario", "view_traces"]


@dataclasses.dataclass
class LiveOutcome:
    result: RunResult
    recorded: str  # the text added to the scenario file ("" without --record)
    warnings: list[str]


def view_scenario(loaded: LoadedScenario, backend: str, out_dir: Path, *, record: str | None = None,
                  speed: float = 1.0, paused: bool = False, offscreen: bool = False,
                  script: Sequence[ScriptEntry] = (), camera: str = "lab") -> LiveOutcome:  # fmt: skip
    """Run ``loaded`` live on ``backend``; the result, and what ``--record`` added to the file."""
    from reports.scene3d.framing import LAB_CAMERA, frame_camera
    from reports.scene3d.model import BodyTrack, SceneModel
    from runner.view.tap import scene_entities

    plan: RecordPlan | None = plan_record(loaded, record) if record else None
    problem = display_problem(offscreen)
    if problem:
        raise ViewUnavailable(problem)
    program = build_program(loaded)
    world = program.world
    warnings = [
        f"the scenario handles `{name}`, which the viewer keeps for itself ({RESERVED[name]}); it cannot be played"
        for name in sorted(set(program.handlers) & set(RESERVED))
    ]
    specs = json.loads(dumps([body_spec_record(b) for b in world.bodies]))  # as the trace's metadata has them
    model = SceneModel.from_specs(specs)
    model.updates = []
    model.add_update(0.0, scene_entities(world.bodies, solid_visuals(program), joints=world.joints))
    targets = [b.pos for b in world.bodies if b.shape.kind.value != "plane"]
    cam = LAB_CAMERA
    if camera == "auto":
        for b in world.bodies:
            model.tracks[b.name] = BodyTrack(*_still(b.pos, b.quat))
        cam = frame_camera([model]).with_aspect(4 / 3)
        model.tracks.clear()
    shown = record or loaded.variant
    title = f"scenario view: {loaded.model.scenario} / {shown} on {backend}"
    hud = Hud(title=f"{loaded.model.scenario}  |  {loaded.variant}  |  {backend}", end_time=program.steps * world.dt,
              recording=record or "")  # fmt: skip
    from reports.scene3d.panda import PandaScene
    from runner.view.live import LiveRun
    from runner.view.window import ViewWindow

    scene = PandaScene(model, start={b.name: (b.pos, b.quat) for b in world.bodies})
    window = ViewWindow(title, [scene], hud, offscreen=offscreen, camera=cam, targets=targets)
    events = named_events(program.handlers, loaded.model.assertions) - set(RESERVED)
    live = LiveRun(window, model, hud, events=events, dt=world.dt, steps=program.steps, speed=speed, paused=paused,
                   script=script, sounds={n: i.path for n, i in program.sounds.items()})  # fmt: skip
    case = dataclasses.replace(loaded, variant=record) if record else loaded
    try:
        result = run_loaded(case, backend, out_dir, force=True, drive=live.drive)
        live.result = result
        live.linger()
    finally:
        window.destroy()
    recorded = ""
    if plan is not None:
        recorded = write_record(plan, loaded, live.played, world.dt, result.verdicts, backend, engine_version(backend))
    return LiveOutcome(result, recorded, warnings)


def _still(pos: Sequence[float], quat: Sequence[float]) -> tuple[Any, Any, Any]:
    import numpy as np

    return np.zeros(1), np.asarray([pos], float), np.asarray([quat], float)


def view_traces(paths: Sequence[Path], *, at: float = 0.0, paused: bool = False, speed: float = 1.0,
                offscreen: bool = False, script: Sequence[ScriptEntry] = (), camera: str = "auto") -> str:  # fmt: skip
    """Replay ``paths`` side by side until the window is closed; where the replay was then (time, mode)."""
    problem = display_problem(offscreen)
    if problem:
        raise ViewUnavailable(problem)
    from runner.view.replay import Replay

    replay = Replay(paths, offscreen=offscreen, at=at, paused=paused, speed=speed, script=script, camera=camera)
    try:
        replay.run()
    finally:
        replay.window.destroy()
    return f"replay closed at t = {replay.t:.3f} s ({'playing' if replay.playing else 'paused'})"
