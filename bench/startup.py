"""Benchmark 11: start-up. A one-step `scenario run` on MuJoCo against ``python -c 'import mujoco'`` in the
same environment (issue 29: at most 1.5x), with `scenario validate` of the same file beside them.

Each command is a fresh process (``sys.executable``, this checkout on ``PYTHONPATH``), timed by its wall
clock and by the CPU time (user + system) of the process and its children (``getrusage``; on a shared
machine other programs' load lengthens the wall time, not this: the target is taken on it); the three are
run in turn, the order rotated each round, and the figures are medians. Where the time
goes: one more run of each command under ``python -X importtime``, its modules' own import times summed by
group (the flag itself slows imports a little, so the groups are shares of the imports, not of the wall
time); what the imports leave of a run is the interpreter's start, loading and validating the file, the
engine's build, the step, the trace and the case's child process.
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from backends.registry import entry
from runner.cli.entry import HEADLESS

ROOT = Path(__file__).resolve().parent.parent
ONE_STEP = ROOT / "bench" / "scenarios" / "one_step.yaml"
ENGINE = "mujoco"  # issue 29 states the start-up target for this engine (its one name in this file)
#: the engine's import name, from the registry
MODULE = entry(ENGINE).module
#: issue 29: a one-step `scenario run` on MuJoCo against importing MuJoCo
TARGET_RATIO = 1.5
#: module name prefixes -> the group they are shown in (first match wins)
GROUPS = (
    ("runner.language.model", "the scenario language's pydantic models (runner/language/model_*.py)"),
    ("pydantic", "pydantic, pydantic_core, annotated_types"),
    ("annotated_types", "pydantic, pydantic_core, annotated_types"),
    ("typing_extensions", "pydantic, pydantic_core, annotated_types"),
    (MODULE, f"{MODULE} (and its renderer's glfw)"),
    ("glfw", f"{MODULE} (and its renderer's glfw)"),
    ("numpy", "numpy"),
    ("rich", "rich"),
    ("pygments", "rich"),
    ("google.protobuf", "protobuf, foxglove schemas, mcap (the trace)"),
    ("foxglove", "protobuf, foxglove schemas, mcap (the trace)"),
    ("mcap", "protobuf, foxglove schemas, mcap (the trace)"),
    ("yaml", "yaml"),
    ("importlib.metadata", "importlib.metadata, email (entry-point scans: MuJoCo's plugins, pydantic's plugin loader)"),
    ("email", "importlib.metadata, email (entry-point scans: MuJoCo's plugins, pydantic's plugin loader)"),
    ("runner", "runner (the rest)"),
    ("backends", "backends"),
    ("reports", "reports"),
)


@dataclass
class StartupFigures:
    seconds: dict[str, list[float]] = field(default_factory=dict)  # command -> per round, wall
    cpu: dict[str, list[float]] = field(default_factory=dict)  # command -> per round, user + system
    imports: dict[str, dict[str, float]] = field(default_factory=dict)  # command -> group -> seconds
    statuses: dict[str, set[int]] = field(default_factory=dict)

    def median(self, name: str) -> float:
        return statistics.median(self.seconds[name])

    def cpu_median(self, name: str) -> float:
        return statistics.median(self.cpu[name])

    @property
    def ratio(self) -> float:
        """The target's ratio: CPU time of the one-step run over that of importing the engine."""
        return self.cpu_median("run") / self.cpu_median("import")

    @property
    def wall_ratio(self) -> float:
        return self.median("run") / self.median("import")


#: the command whose time is taken in the environment as it is (bytecode as the environment allows)
AS_IS = "run, as the environment is"
#: the engine's import with the settings the command gives itself (runner.cli.entry.HEADLESS: MuJoCo without
#: its GL context): what the run's own import of the engine costs, beside the target's plain import
HEADLESS_IMPORT = "import, headless"


def commands(out: Path) -> dict[str, list[str]]:
    py = sys.executable
    run_ = [py, "-m", "runner", "run", str(ONE_STEP), "--backend", ENGINE, "--quiet", "--out", str(out)]
    return {
        "import": [py, "-c", f"import {MODULE}"],
        HEADLESS_IMPORT: [py, "-c", f"import {MODULE}"],
        "validate": [py, "-m", "runner", "validate", str(ONE_STEP)],
        "run": run_,
        AS_IS: run_,
    }


def _env(name: str = "", pycache: Path | None = None) -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    if name == HEADLESS_IMPORT:
        env = {**HEADLESS, **env}  # as the command sets them: unless the environment has them already
    if name != AS_IS and pycache is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(pycache)
    return env


def group_of(module: str) -> str:
    return next((g for prefix, g in GROUPS if module == prefix or module.startswith((prefix + ".", prefix + "_"))),
                "other")  # fmt: skip


def import_groups(stderr: str) -> dict[str, float]:
    """``-X importtime`` output -> seconds of the modules' own import time per group."""
    out: dict[str, float] = {}
    for line in stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        own, _, name = line[len("import time:") :].split("|")
        group = group_of(name.strip())
        out[group] = out.get(group, 0.0) + int(own) / 1e6
    return out


def run(reps: int = 7, log: Callable[[str], None] = print) -> StartupFigures:
    fig = StartupFigures()
    with tempfile.TemporaryDirectory(prefix="bench-startup-") as tmp, \
            tempfile.TemporaryDirectory(prefix="bench-startup-pyc-") as pyc:  # fmt: skip
        cmds = commands(Path(tmp))
        names = list(cmds)
        for rep in range(reps + 1):  # the first round warms the file cache and is not counted
            turn = rep % len(names)
            for name in names[turn:] + names[:turn]:
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                start = time.perf_counter()
                done = subprocess.run(cmds[name], capture_output=True, text=True, env=_env(name, Path(pyc)), cwd=ROOT,
                                      check=False)  # fmt: skip
                seconds = time.perf_counter() - start
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
                fig.statuses.setdefault(name, set()).add(done.returncode)
                if rep:
                    fig.seconds.setdefault(name, []).append(seconds)
                    fig.cpu.setdefault(name, []).append(cpu)
        for name, cmd in cmds.items():
            if name == AS_IS:
                continue
            done = subprocess.run([cmd[0], "-X", "importtime", *cmd[1:]], capture_output=True, text=True,
                                  env=_env(name, Path(pyc)), cwd=ROOT, check=False)  # fmt: skip
            fig.imports[name] = import_groups(done.stderr)
    fig.seconds = {n: fig.seconds[n] for n in names}
    fig.cpu = {n: fig.cpu[n] for n in names}
    log("  startup: " + ", ".join(f"{n} {fig.cpu_median(n):.3f} s CPU ({fig.median(n):.3f} wall)" for n in names)
        + f"; run/import {fig.ratio:.2f}")  # fmt: skip
    return fig


def target_rows(fig: StartupFigures | None) -> list[tuple[str, str, bool, str]]:
    if fig is None:
        return []
    run_imports = fig.imports.get("run", {})
    top = sorted(((v, k) for k, v in run_imports.items() if not k.startswith(MODULE)), reverse=True)[:3]
    where = "; ".join(f"{k} {v * 1e3:.0f} ms" for v, k in top)
    as_is = (f"; bytecode as the environment allows: {fig.cpu_median(AS_IS) / fig.cpu_median('import'):.2f}"
             if AS_IS in fig.cpu else "")  # fmt: skip
    if HEADLESS_IMPORT in fig.cpu:
        as_is += (f"; against the import with the command's own engine settings ({_settings()}): "
                  f"{fig.cpu_median('run') / fig.cpu_median(HEADLESS_IMPORT):.2f}")
    return [(f"start-up: one-step `scenario run` on {ENGINE} / `python -c 'import {ENGINE}'` <= {TARGET_RATIO:g}",
             f"{fig.ratio:.2f} (CPU {fig.cpu_median('run'):.2f} s vs {fig.cpu_median('import'):.2f} s; wall "
             f"{fig.wall_ratio:.2f}{as_is})",
             fig.ratio <= TARGET_RATIO, f"imports beyond {MODULE}'s (-X importtime, section 11): {where}")]  # fmt: skip


def _settings() -> str:
    return " ".join(f"{k}={v}" for k, v in HEADLESS.items())


def _bytecode_note() -> str:
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        return "set: this checkout compiled from source at every start"
    return "not set"


def render(fig: StartupFigures | None) -> list[str]:
    if fig is None:
        return []
    names = [n for n in ("import", HEADLESS_IMPORT, "validate", "run", AS_IS) if n in fig.seconds]
    out = [
        "## 11. Start-up: a one-step `scenario run` against importing the engine",
        "",
        f"bench/startup.py: `bench/scenarios/one_step.yaml` (one 10 ms step of a box), each command a fresh "
        f"process, {len(fig.seconds['run'])} interleaved rounds after one uncounted, medians of the CPU time of "
        f"the process and its children (user + system) and of the wall time; bytecode cached in the benchmark's "
        f"own folder (`PYTHONPYCACHEPREFIX`, written in the uncounted round) except for the last row, which runs "
        f"with the environment as it is (`PYTHONDONTWRITEBYTECODE` "
        f"{_bytecode_note()}); "
        f"exit codes seen: " + ", ".join(f"{n} {sorted(fig.statuses[n])}" for n in names) + ".",
        "",
        "| command | CPU (s) | / import | wall (s) | / import | wall, each round (s) |",
        "|---|---|---|---|---|---|",
    ]
    label = {"import": f"`python -c 'import {ENGINE}'`",
             HEADLESS_IMPORT: f"the same import with the command's own settings, `{_settings()}`",
             "validate": "`scenario validate one_step.yaml`",
             "run": f"`scenario run one_step.yaml --backend {ENGINE} --quiet`",
             AS_IS: "the same run, bytecode as the environment allows"}  # fmt: skip
    for n in names:
        runs = ", ".join(f"{s:.2f}" for s in fig.seconds[n])
        out.append(f"| {label[n]} | {fig.cpu_median(n):.3f} | {fig.cpu_median(n) / fig.cpu_median('import'):.2f} "
                   f"| {fig.median(n):.3f} | {fig.median(n) / fig.median('import'):.2f} | {runs} |")  # fmt: skip
    names = [n for n in names if n in fig.imports]
    groups = sorted({g for d in fig.imports.values() for g in d}, key=lambda g: -fig.imports.get("run", {}).get(g, 0))
    out += ["", "Where the time goes: the modules' own import time by group (ms, `-X importtime`, one run each):", "",
            "| group | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]  # fmt: skip
    for g in groups:
        out.append(f"| {g} | " + " | ".join(f"{fig.imports.get(n, {}).get(g, 0.0) * 1e3:.0f}" for n in names) + " |")
    totals = " | ".join(f"{sum(fig.imports.get(n, {}).values()) * 1e3:.0f}" for n in names)
    out += [f"| **all imports** | {totals} |", ""]
    return out
