"""Benchmark 8: robots on each engine: build time, and the runner's step against the engine's own loop doing
the same reads (issue 29: at most 1.5x on PyBullet and MuJoCo).

Two robots: the KUKA arm (`scenarios/robots/kuka_arm.yaml`, URDF, 7 servoed joints, 8 links) and an 8-joint
MJCF quadruped (`bench/scenarios/quadruped.yaml`). Each (engine, robot) is a child process
(``python -m bench.robot <backend> <robot> <reps>``) that runs, interleaved, ``reps`` times each:

* *native*: the adapter's own engine world (same model, same settings: the same physics) stepped and read
  by hand (bench/raw_<engine>.py ``ROBOT_LOOP``): the servos' rates (the same targets the runner's servos
  read, step by step, recorded from a runner run), the engine's step, every link's pose and velocity and
  every joint's position, velocity and motor force;
* *runner*: ``run_loaded`` without a trace, and *runner+trace* with it: the time of ``Session.run`` (the
  step loop; build, compile and the trace file's opening and closing are outside it);
* *parts*: the untraced runner with its parts timed (bench/instrument.py; adds about 0.3 us per call).

Per-step figures are CPU seconds of the process (``time.process_time``: other programs' load on a shared
machine does not lengthen them as it does wall time), medians over the repetitions; the ratio is runner /
native. *same physics*: the largest
joint position difference between the native loop and the runner after the last step.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = {
    "kuka arm": ROOT / "scenarios" / "robots" / "kuka_arm.yaml",
    "quadruped": ROOT / "bench" / "scenarios" / "quadruped.yaml",
}
#: issue 29: the runner's step over a robot against the engine's own loop with the same reads
TARGET_RATIO = 1.5
TIMEOUT_S = 600.0
#: CPU time of the process: on a shared machine other programs' load lengthens wall time, not this (the
#: trace's compression thread is counted with the run)
CLOCK = time.process_time
#: the parts of the runner's untraced step, in the order they are shown
PARTS = ("engine step", "engine reads", "motor commands", "servos (beyond the commands)", "energy watchdog",
         "assertions", "events and conditions", "step loop, other")  # fmt: skip
#: the parts that are the scenario's own per-step work, beyond the reads and commands the native loop shares:
#: the energy watchdog (docs/semantics.md), the assertions checked every step and the servo law
SCENARIO_WORK = ("energy watchdog", "assertions", "servos (beyond the commands)")


@dataclass(frozen=True)
class RobotFigures:
    backend: str
    robot: str = ""
    build_s: float | None = None  # None: refused or failed (``note`` says why)
    steps: int = 0
    native_ms: float = 0.0  # per step, medians
    runner_ms: float = 0.0
    traced_ms: float = 0.0
    parts: dict[str, float] = field(default_factory=dict)  # ms per step
    same_physics: float = float("nan")  # rad, largest joint position difference at the end
    native_loop: bool = True  # False: no hand-written robot loop for this engine
    note: str = ""

    @property
    def ratio(self) -> float:
        return self.runner_ms / self.native_ms if self.native_ms else float("nan")

    @property
    def ratio_traced(self) -> float:
        return self.traced_ms / self.native_ms if self.native_ms else float("nan")


def measure(backend: str, robot: str, reps: int) -> RobotFigures:
    cmd = [sys.executable, "-m", "bench.robot", backend, robot, str(reps)]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=TIMEOUT_S, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return RobotFigures(backend, robot, note=f"not done within {TIMEOUT_S:g} s")
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["?"])[-1]
        return RobotFigures(backend, robot, note=f"exit {done.returncode}: {last[:200]}")
    return RobotFigures(**json.loads(done.stdout.strip().splitlines()[-1]))


def run(backends: Sequence[str], reps: int = 5, log: Callable[[str], None] = print) -> list[RobotFigures]:
    out = []
    for robot in ROBOTS:
        for backend in backends:
            fig = measure(backend, robot, reps)
            out.append(fig)
            if fig.build_s is None:
                log(f"  robot {robot} {backend}: {fig.note[:160]}")
            else:
                log(f"  robot {robot} {backend}: build {fig.build_s:.3f} s, native {fig.native_ms:.3f} ms/step, "
                    f"runner {fig.runner_ms:.3f} ({fig.ratio:.2f}x), traced {fig.traced_ms:.3f}")  # fmt: skip
    return out


def _ms(x: float) -> str:
    return f"{x:.3f}" if x == x and x else ""


def target_rows(figs: Sequence[RobotFigures]) -> list[tuple[str, str, bool, str]]:
    """(target, measured, met, where the time goes) for the report's target table."""
    rows = []
    for f in figs:
        if f.build_s is None or not f.native_loop:
            continue
        excess = f.runner_ms - f.native_ms
        top = sorted(((v, k) for k, v in f.parts.items() if k != "engine step"), reverse=True)[:3]
        where = "; ".join(f"{k} {v:.3f} ms/step" for v, k in top)
        own = sum(f.parts.get(k, 0.0) for k in SCENARIO_WORK)
        rows.append((f"robot step, {f.backend}, {f.robot}: runner (no trace) / native loop with the same reads "
                     f"<= {TARGET_RATIO:g}", f"{f.ratio:.2f} (with trace {f.ratio_traced:.2f})",
                     f.ratio <= TARGET_RATIO,
                     f"native {f.native_ms:.3f} ms/step, runner {f.runner_ms:.3f} (+{excess:.3f}): "
                     f"{where}; the per-step work the native loop does not do ({', '.join(SCENARIO_WORK)}) "
                     f"{own:.3f} ms/step alone makes {(f.native_ms + own) / f.native_ms:.2f}x"))  # fmt: skip
    return rows


def render(figs: Sequence[RobotFigures]) -> list[str]:
    out = [
        "## 8. Robots: the KUKA arm (URDF, 7 servoed joints, 8 links as convex hulls) and an 8-joint MJCF quadruped",
        "",
        "bench/robot.py: CPU time per step, medians of interleaved repetitions (build excluded). *native*: the "
        "adapter's engine world stepped and read by hand with the same reads (bench/raw_<engine>.py `ROBOT_LOOP`); "
        "*runner*: the step loop (`Session.run`) without a trace, and with it; *same physics*: largest joint "
        "position difference (rad) between the two after the last step.",
        "",
        "| backend | robot | build (s) | steps | native (ms/step) | runner (ms/step) | ratio | runner + trace "
        "(ms/step) | ratio | same physics (rad) | note |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for f in figs:
        if f.build_s is None:
            out.append(f"| {f.backend} | {f.robot} | | | | | | | | | {f.note} |")
            continue
        ratio = f"{f.ratio:.2f}" if f.native_loop else ""
        ratio_t = f"{f.ratio_traced:.2f}" if f.native_loop else ""
        same = f"{f.same_physics:.1e}" if f.native_loop else ""
        out.append(f"| {f.backend} | {f.robot} | {f.build_s:.3f} | {f.steps} | {_ms(f.native_ms)} | "
                   f"{f.runner_ms:.3f} | {ratio} | {f.traced_ms:.3f} | {ratio_t} | {same} | {f.note} |")  # fmt: skip
    out += ["", "Where the runner's untraced step goes (ms per step, the instrumented runs' medians; *engine step*: "
            "the adapter's `step()`; *engine reads*: `body_states`, `joint_states` (and `contacts` where asked); "
            "*motor commands*: the adapter's `set_motor` and `set_motors`):", "",
            "| backend | robot | " + " | ".join(PARTS) + " |", "|---|---|" + "---|" * len(PARTS)]  # fmt: skip
    for f in figs:
        if f.parts:
            out.append(f"| {f.backend} | {f.robot} | " + " | ".join(f"{f.parts.get(k, 0.0):.3f}" for k in PARTS) + " |")
    return [*out, ""]


# --- the child process ----------------------------------------------------------------------------------------


def _native_servo(program: Any, joint: int, spec: Any) -> Any:
    """The runner's servo as the native loop drives it: its rate clamped to vmax and to the joint's velocity
    limit (two symmetric clamps are one, to the smaller bound: the same numbers), its fmax within the joint's
    effort limit (runner.sim.servo), read from the joint's start plus its stated zero."""
    from runner.compile.joints import capped

    from .raw_common import Servo

    dyn = program.world.joints[joint].dynamics
    bounds = [b for b in (spec.vmax, dyn.velocity) if b is not None]
    return Servo(joint, spec.gain, capped(0.0, spec.fmax, dyn)[1], min(bounds) if bounds else None,
                 program.joint_zeros.get(spec.joint, 0.0))  # fmt: skip


def _child(argv: Sequence[str]) -> int:
    import importlib

    import numpy as np

    from backends.errors import UnsupportedFeature
    from backends.registry import check_capabilities, get_backend
    from runner.compile.program import build_program
    from runner.language.load import load_scenario
    from runner.sim.assertions import AssertionTracker
    from runner.sim.energy import EnergyWatch
    from runner.sim.run import run_loaded
    from runner.sim.servo import Servos, servo_specs
    from runner.sim.session import Session

    from . import instrument as ins

    backend, robot, reps = argv[0], argv[1], int(argv[2])
    loaded = load_scenario(ROBOTS[robot])
    program = build_program(loaded)
    cls = get_backend(backend)
    try:
        check_capabilities(cls, program.world)
    except UnsupportedFeature as exc:
        missing = ", ".join(sorted(c.value for c in exc.missing))
        print(json.dumps({"backend": backend, "robot": robot, "note": f"refused up front: needs {missing}"}))
        return 0
    try:
        make_loop = importlib.import_module(f"bench.raw_{backend}").ROBOT_LOOP
    except (ImportError, AttributeError):
        make_loop = None
    joint_index = {j.name: i for i, j in enumerate(program.world.joints)}
    servos = [_native_servo(program, joint_index[s.joint], s) for s in servo_specs(loaded.model)]
    targets: list[list[float]] = []
    final: dict[str, np.ndarray] = {}
    seconds: dict[str, list[float]] = {}
    parts: list[dict[str, float]] = []
    builds: list[float] = []
    statuses: set[str] = set()
    record = Servos.targets

    def recorded(self: Servos, resolver: Any) -> list[float]:
        out = record(self, resolver)
        targets.append(out)
        return out

    def drive(session: Session) -> Any:
        result = session.run()
        final["q"] = session.snapshot.joints.position.copy()
        return result

    def runner(traced: bool, out: Path, split_parts: bool = False) -> float:
        groups: dict[str, tuple[type, tuple[str, ...]]] = {"loop": (Session, ("run",))}
        if split_parts:
            groups |= {
                "engine": (cls, ins.ENGINE_STEP + ins.ENGINE_READS + ins.ENGINE_INPUTS + ins.ENGINE_SETUP),
                "servos": (Servos, ("drive",)),
                "energy": (EnergyWatch, ("check",)),
                "assert": (AssertionTracker, ("on_step",)),
                "detect": (Session, ("_detect",)),
            }
        with ins.timed(groups, CLOCK) as split:
            result = run_loaded(loaded, backend, out if traced else None, drive=drive)
        statuses.add(result.status)
        steps = max(result.steps, 1)
        if split_parts:
            t = {k: v / steps * 1e3 for k, v in split.seconds.items()}
            builds.append(split.total("engine", ins.ENGINE_SETUP))
            step, reads = t.get("engine.step", 0.0), sum(t.get(f"engine.{m}", 0.0) for m in ins.ENGINE_READS)
            motors = t.get("engine.set_motor", 0.0) + t.get("engine.set_motors", 0.0)
            drive_ms = t.get("servos.drive", 0.0)
            named = {"engine step": step, "engine reads": reads, "motor commands": motors,
                     "servos (beyond the commands)": drive_ms - motors, "energy watchdog": t.get("energy.check", 0.0),
                     "assertions": t.get("assert.on_step", 0.0),
                     "events and conditions": t.get("detect._detect", 0.0)}  # fmt: skip
            loop = t.get("loop.run", 0.0)
            named["step loop, other"] = loop - sum(named.values())
            parts.append(named)
        return split.total("loop") / steps

    def native() -> float:
        adapter = cls(program.world)
        try:
            loop = make_loop(adapter, servos)
            start = CLOCK()
            for row in targets:
                loop.step(row)
                loop.read()
            seconds_per_step = (CLOCK() - start) / len(targets)
            q = loop.joint_positions()
            final["native_q"] = np.array([q.get(k, np.nan) for k in range(len(program.world.joints))])
        finally:
            adapter.close()
        return seconds_per_step

    Servos.targets = recorded  # type: ignore[method-assign]
    with tempfile.TemporaryDirectory(prefix="bench-robot-") as tmp:
        out = Path(tmp)
        try:
            runner(False, out)  # records the servos' targets, step by step, for the native loop
        finally:
            Servos.targets = record  # type: ignore[method-assign]
        runner_q = final.get("q")  # none when the run ended by an engine failure (``note`` gives its status)
        modes = ["runner", "runner+trace", "parts"] + (["native"] if make_loop is not None else [])
        for rep in range(reps):
            turn = rep % len(modes)
            for mode in modes[turn:] + modes[:turn]:
                if mode == "native":
                    s = native()
                else:
                    s = runner(mode == "runner+trace", out, split_parts=mode == "parts")
                seconds.setdefault(mode, []).append(s)
    same = float("nan")
    if make_loop is not None and runner_q is not None and "native_q" in final:
        moving = ~np.isnan(runner_q)
        same = float(np.abs(runner_q[moving] - final["native_q"][moving]).max()) if moving.any() else 0.0
    med = {k: statistics.median(v) * 1e3 for k, v in seconds.items()}
    names = parts[0].keys() if parts else ()
    print(json.dumps({
        "backend": backend, "robot": robot, "build_s": statistics.median(builds), "steps": len(targets),
        "native_ms": med.get("native", 0.0), "runner_ms": med["runner"], "traced_ms": med["runner+trace"],
        "parts": {k: statistics.median(p[k] for p in parts) for k in names}, "same_physics": same,
        "native_loop": make_loop is not None,
        "note": "" if statuses == {"passed"} else f"runs: {', '.join(sorted(statuses))}",
    }))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1:]))
