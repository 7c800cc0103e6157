"""Benchmark 8: the robot arm (`scenarios/robots/kuka_arm.yaml`) on each engine: build time and the runner's
per-step overhead beyond the engine.

Each engine is a child process (``python -m bench.robot <backend>``) that loads and compiles the scenario,
then, where the adapter accepts the robot capabilities, times the adapter's construction (``create_backend``)
and a whole run without a trace, with the adapter's ``_step`` wrapped by ``perf_counter`` calls: the runner's
per-step overhead is (run time - construction - engine steps) / steps, which includes the position servos'
seven ``set_motor`` calls per step and the reads. Every adapter maps the arm's capabilities (docs/robots.md);
an engine that refuses it (one without them) is listed with its refusal, and a run that does not pass is
measured all the same but noted (its figures would not be the arm's).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ARM = ROOT / "scenarios" / "robots" / "kuka_arm.yaml"
TIMEOUT_S = 300.0


@dataclass(frozen=True)
class RobotFigures:
    backend: str
    build_s: float | None  # None: refused or failed (``note`` says why)
    steps: int = 0
    engine_ms: float = 0.0  # per step, the adapter's _step
    runner_ms: float = 0.0  # per step, everything else of the run
    note: str = ""


def measure(backend: str) -> RobotFigures:
    cmd = [sys.executable, "-m", "bench.robot", backend]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=TIMEOUT_S, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return RobotFigures(backend, None, note=f"not done within {TIMEOUT_S:g} s")
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["?"])[-1]
        return RobotFigures(backend, None, note=f"exit {done.returncode}: {last[:200]}")
    return RobotFigures(**json.loads(done.stdout.strip().splitlines()[-1]))


def run(backends: Sequence[str], log: Callable[[str], None] = print) -> list[RobotFigures]:
    out = []
    for backend in backends:
        fig = measure(backend)
        out.append(fig)
        if fig.build_s is None:
            log(f"  robot arm {backend}: {fig.note[:160]}")
        else:
            log(
                f"  robot arm {backend}: build {fig.build_s:.3f} s, engine {fig.engine_ms:.3f} ms/step, "
                f"runner {fig.runner_ms:.3f} ms/step"
            )
    return out


def render(figs: Sequence[RobotFigures]) -> list[str]:
    out = [
        "## 8. Robot arm: `scenarios/robots/kuka_arm.yaml` (7 servoed joints, 8 links as convex hulls)",
        "",
        "| backend | build (s) | steps | engine (ms/step) | runner overhead (ms/step) | note |",
        "|---|---|---|---|---|---|",
    ]
    for f in figs:
        if f.build_s is None:
            out.append(f"| {f.backend} | | | | | {f.note} |")
        else:
            out.append(
                f"| {f.backend} | {f.build_s:.3f} | {f.steps} | {f.engine_ms:.3f} | {f.runner_ms:.3f} | {f.note} |"
            )
    return [
        *out,
        "",
        "*build*: the adapter's constructor; *engine*: its `_step`; *runner overhead*: the rest "
        "of a run without a trace (servos, reads, assertions) per step.",
        "",
    ]


def _child(argv: Sequence[str]) -> int:
    from backends.errors import UnsupportedFeature
    from backends.registry import check_capabilities, get_backend
    from runner.compile.program import build_program
    from runner.language.load import load_scenario
    from runner.sim.run import run_loaded

    backend = argv[0]
    loaded = load_scenario(ARM)
    cls = get_backend(backend)
    try:
        check_capabilities(cls, build_program(loaded).world)
    except UnsupportedFeature as exc:
        missing = ", ".join(sorted(c.value for c in exc.missing))
        print(json.dumps({"backend": backend, "build_s": None, "note": f"refused up front: needs {missing}"}))
        return 0
    spent = {"step": 0.0, "build": 0.0}
    step, init = cls._step, cls.__init__

    def timed_step(self: object) -> None:
        start = time.perf_counter()
        step(self)  # type: ignore[arg-type]
        spent["step"] += time.perf_counter() - start

    def timed_init(self: object, world: object) -> None:
        start = time.perf_counter()
        init(self, world)  # type: ignore[arg-type]
        spent["build"] += time.perf_counter() - start

    cls._step, cls.__init__ = timed_step, timed_init  # type: ignore[method-assign]
    try:
        start = time.perf_counter()
        result = run_loaded(loaded, backend, None)
        wall = time.perf_counter() - start
    finally:
        cls._step, cls.__init__ = step, init  # type: ignore[method-assign]
    steps = max(result.steps, 1)
    runner = (wall - spent["build"] - spent["step"]) / steps * 1e3
    print(
        json.dumps(
            {
                "backend": backend,
                "build_s": spent["build"],
                "steps": result.steps,
                "engine_ms": spent["step"] / steps * 1e3,
                "runner_ms": runner,
                "note": "" if result.passed else f"the run {result.status}: {result.failure or 'see its verdicts'}",
            }
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1:]))
