"""Run one loaded scenario variant on one backend, writing its trace: the library entry point."""

from __future__ import annotations

import json
import re
import time as wallclock
from collections.abc import Callable
from pathlib import Path
from typing import Any

from backends.errors import EngineFailure
from backends.registry import check_capabilities, get_backend
from backends.types import CompiledWorld
from reports import trace_format as tf
from runner import interrupts
from runner.compile.asserted import asserted_quantities
from runner.compile.program import build_program
from runner.language.load import LoadedScenario
from runner.sim.budget import Watchdog
from runner.sim.session import RunResult, Session
from runner.trace.output import Claim, write_error
from runner.version import tool_version


def trace_path(out_dir: Path, loaded: LoadedScenario, backend: str) -> Path:
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{loaded.model.scenario}__{loaded.variant}__{backend}")
    return out_dir / f"{stem}.mcap"


def solid_visuals(program) -> list:  # noqa: ANN001 - runner-internal
    """The collision solids as the trace's scene draws them (scaled, in their body's frame)."""
    from runner.trace.writer import SolidVisual

    out = []
    for node in program.nodes:
        body = program.world.bodies[node.body].name
        scale = program.start_scale[body]
        for s in node.solids:
            out.append(
                SolidVisual(
                    node=node.name,
                    body=body,
                    kind=s.kind,
                    center=tuple(float(c) * scale for c in s.center),
                    radius=s.radius * scale,
                    size=tuple(float(c) * 2 * scale for c in s.half) if s.half is not None else (0.0, 0.0, 0.0),
                    vertices=tuple(tuple(float(c) * scale for c in v) for v in s.vertices)
                    if s.vertices is not None
                    else (),
                )
            )
    return out


def run_loaded(
    loaded: LoadedScenario,
    backend_name: str,
    out_dir: Path | None,
    progress: Callable[[int, int], None] | None = None,
    force: bool = True,
    record_every: int = 1,
    trace_process: bool = False,
    drive: Callable[[Session], RunResult] | None = None,
    budget: float | None = None,
    claimed: bool = False,
) -> RunResult:
    """Build, run and record one case. Engine failures come back as a result with status engine-failure;
    an interruption (KeyboardInterrupt) finishes the trace as interrupted and propagates.

    ``record_every``: the trace gets every k-th step and the last (assertions still check every step);
    ``trace_process``: the trace is formatted and written by a second process (runner.trace.process);
    ``drive``: what runs the session instead of ``Session.run`` (a live run, runner.view);
    ``budget``: wall-clock seconds the run may take from here (default: ``world.budget``, else none;
    runner.sim.budget); ``claimed``: the caller already owns the case's output names
    (:class:`runner.trace.output.Claim`), else this call takes them (``force``: also over files this
    tool did not write)."""
    started = wallclock.perf_counter()
    program = build_program(loaded)
    cls = get_backend(backend_name)
    interrupts.check()  # a signal during the engine's import is an interruption, never a broken import
    check_capabilities(cls, program.world)
    budget = budget if budget is not None else loaded.model.world.budget
    watchdog = None if budget is None else Watchdog(budget, program.steps, program.world.dt, started, backend_name)
    claim: Claim | None = None
    if out_dir is not None:
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise write_error(exc, f"the trace folder {out_dir}") from exc
        if not claimed:
            claim = Claim(trace_path(out_dir, loaded, backend_name), force=force)
    try:
        backend = cls(program.world)
    except BaseException:
        if claim is not None:
            claim.release()
        raise
    try:
        interrupts.check()  # building a big world can take long: a signal meanwhile ends the run here
        if out_dir is None:
            return _run(program, loaded, backend, None, progress, record_every, watchdog, drive)
        from runner.trace.writer import TraceMeta, TraceWriter

        world = program.world
        meta = TraceMeta(
            scenario=loaded.model.scenario,
            variant=loaded.variant,
            backend=backend_name,
            backend_version=cls.engine_version(),
            engine_settings=backend.settings(),
            dt=world.dt,
            substeps=world.substeps,
            duration=world.duration,
            tool_version=tool_version(),
            scenario_sha256=loaded.sha256,
            scenario_path=loaded.path.name,
            schema_version=loaded.model.schema_version,
            bodies=world.bodies,
            joints=world.joints,
            state_names=list(loaded.model.state),
            extra={
                "overrides": json.dumps([[k, v] for k, v in loaded.overrides], default=str),
                tf.KEY_ASSERTED: json.dumps(asserted_quantities(program)),
                **({tf.KEY_SENSORS: json.dumps(program.sensors)} if program.sensors else {}),
                **({"record_every": str(record_every)} if record_every > 1 else {}),
                **_arrow_scale(loaded, world),
            },
        )
        writer: Any = TraceWriter
        if trace_process:
            from runner.trace.process import BackgroundTraceWriter

            writer = BackgroundTraceWriter
        with interrupts.deferred(), writer(trace_path(out_dir, loaded, backend_name), meta) as trace:
            _attach_sources(trace, loaded, program)
            trace.scene(0.0, solid_visuals(program))
            return _run(program, loaded, backend, trace, progress, record_every, watchdog, drive)
    finally:
        backend.close()
        if claim is not None:
            claim.release()


def _run(  # noqa: ANN001
    program, loaded: LoadedScenario, backend, trace, progress, record_every: int = 1,
    watchdog: Watchdog | None = None, drive: Callable[[Session], RunResult] | None = None,
) -> RunResult:  # fmt: skip
    session = Session(program, backend, trace, progress, record_every, watchdog)
    try:
        result = session.run() if drive is None else drive(session)
    except EngineFailure as exc:
        result = RunResult(
            program.name,
            loaded.variant,
            backend.name,
            "engine-failure",
            [],
            session.snapshot.time,
            0,
            session.events,
            session.sound_starts,
            0.0,
            failure=str(exc),
            extra={"body": exc.body, "time": exc.time, "last_good": exc.last_good},
            engine_messages=session.engine_messages,
        )
    if trace is not None:
        trace.verdicts(result.end_time, [v.as_dict() for v in result.verdicts])
        if result.failure:
            trace.log(result.end_time, "error", result.failure, "engine")
        summary = {
            "passed": sum(v.passed for v in result.verdicts),
            "failed": sum(not v.passed for v in result.verdicts),
            "end_time": result.end_time,
            "failure": result.failure,
            **({"failure_detail": result.extra} if result.failure else {}),
            **({"engine_messages": result.engine_messages} if result.engine_messages else {}),
        }
        result.trace = str(trace.finish(result.status, summary))
        write_cost(Path(result.trace), result)
    return result


def cost_path(trace: Path) -> Path:
    """Where a run's wall-clock cost is kept: beside the trace, never inside it (traces hold simulated time
    only, so that the same run gives the same bytes)."""
    return trace.with_name(trace.name.removesuffix(".mcap") + ".cost.json")


def write_cost(trace: Path, result: RunResult) -> None:
    simulated = result.end_time
    data = {
        "trace": trace.name,
        "wall_seconds": round(result.wall_seconds, 6),
        "steps": result.steps,
        "simulated_seconds": simulated,
        "steps_per_second": round(result.steps / result.wall_seconds, 3) if result.wall_seconds > 0 else None,
        "real_time_factor": round(simulated / result.wall_seconds, 4) if result.wall_seconds > 0 else None,
    }
    target = cost_path(trace)
    tmp = target.with_name(target.name + ".partial")
    try:
        tmp.write_text(json.dumps(data, indent=2) + "\n")
        tmp.replace(target)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise write_error(exc, str(target)) from exc


def _attach_sources(trace, loaded: LoadedScenario, program) -> None:  # noqa: ANN001
    trace.attach(loaded.path.name, loaded.text.encode(), "application/yaml")
    for name, info in program.sounds.items():
        trace.attach(f"sounds/{name}.wav", info.path.read_bytes(), "audio/wav")


def _arrow_scale(loaded: LoadedScenario, world: CompiledWorld) -> dict[str, str]:
    """The contact arrows' scale (m/N) for the scenario record, when the scenario asks for contact points."""
    if not world.contact_points:
        return {}
    from runner.trace.contact_arrows import KEY_SCALE, default_scale

    scale = loaded.model.trace.contact_arrow_scale
    return {KEY_SCALE: repr(float(scale if scale is not None else default_scale(world)))}
