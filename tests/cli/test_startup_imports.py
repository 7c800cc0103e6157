"""What a command imports (issue 29, start-up): `scenario run` and `scenario validate` import what they use, not
the other commands, the trace reader or the JUnit writer. A check of the imports, not of the time (bench/startup.py
measures that): a module a command does not use, imported at start-up, costs every run."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.engines import INSTALLED
from tests.paths import ROOT

ONE_STEP = ROOT / "bench" / "scenarios" / "one_step.yaml"
#: never needed to run or validate a scenario
NOT_FOR_A_RUN = (
    "reports.trace_reader",
    "mcap_protobuf.decoder",
    "runner.ci.junit",
    "runner.cli.commands.report",
    "runner.cli.commands.compare",
    "runner.cli.commands.view",
    "runner.cli.commands.conformance",
)
#: not needed by a one-step run that passes under --quiet: the verdict table (rich.table: no table is drawn), and in
#: the worker numpy's masked arrays and random generators (the trace's templates and the collision traverser's set
#: up use neither); difflib only hints at a misspelt name, wave only reads a scenario's sounds
NOT_FOR_A_QUIET_PASS = ("rich.table", "numpy.ma", "numpy.random", "difflib", "wave")


def _python(
    args: list[str], cwd: Path, environ: dict[str, str | None] | None = None
) -> subprocess.CompletedProcess[str]:
    """A fresh Python process on this checkout with ``args``, which must succeed; ``environ``: variables set (a
    string) or removed (None) for it."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("PYTEST_CURRENT_TEST", None)
    for name, value in (environ or {}).items():
        if value is None:
            env.pop(name, None)
        else:
            env[name] = value
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=cwd, env=env, check=False,
                          timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return done


def _imported(args: list[str], cwd: Path, environ: dict[str, str | None] | None = None) -> set[str]:
    """The modules a `scenario` command's own process imports (``-X importtime``); ``environ`` as for
    :func:`_python`."""
    err = _python(["-X", "importtime", "-m", "runner", *args], cwd, environ).stderr
    return {line.rsplit("|", 1)[1].strip() for line in err.splitlines() if line.startswith("import time:")}


def test_a_run_imports_neither_the_other_commands_nor_the_trace_reader(tmp_path: Path) -> None:
    modules = _imported(["run", str(ONE_STEP), "--backend", "pybullet", "--quiet", "--out", str(tmp_path)], tmp_path)
    assert "runner.sim.session" in modules and "runner.trace.writer" in modules  # it did run and write its trace
    assert not modules & {*NOT_FOR_A_RUN, *NOT_FOR_A_QUIET_PASS}
    again = _imported(["run", str(ONE_STEP), "--backend", "pybullet", "--quiet", "--out", str(tmp_path)], tmp_path)
    assert "mcap.stream_reader" not in again  # its own trace, recognised without mcap's reader, is replaced


def test_validate_imports_neither_the_step_loop_nor_the_trace(tmp_path: Path) -> None:
    modules = _imported(["validate", str(ONE_STEP)], tmp_path)
    assert "runner.language.load" in modules
    assert not modules & {*NOT_FOR_A_RUN, "runner.sim.session", "runner.trace.writer"}


@pytest.mark.skipif("mujoco" not in INSTALLED, reason="MuJoCo is an optional engine, not installed here")
def test_a_mujoco_run_leaves_mujocos_renderer_unloaded_unless_the_user_asks(tmp_path: Path) -> None:
    """runner.cli.entry.HEADLESS: the command never draws through MuJoCo, so its GL context (GLFW) stays
    unloaded; a MUJOCO_GL the user set is theirs. The worker's imports reach the command's stderr as the
    engine's output, so both processes are seen."""
    run = ["run", str(ONE_STEP), "--backend", "mujoco", "--quiet", "--out", str(tmp_path)]
    modules = _imported(run, tmp_path, {"MUJOCO_GL": None})
    assert "mujoco" in modules and "glfw" not in modules
    assert "glfw" in _imported(run, tmp_path, {"MUJOCO_GL": "glfw"})


def test_the_collector_is_back_on_after_the_imports_with_what_they_made_frozen(tmp_path: Path) -> None:
    """runner.startup: the command's imports run without the cyclic collector, which must be on again for the
    command itself (a long run makes garbage cycles); what the imports made is frozen, once per process."""
    probe = (
        "import gc, sys\n"
        "from runner.cli.main import main\n"
        "code = main(['validate', sys.argv[1]])\n"
        "frozen = gc.get_freeze_count()\n"
        "main(['validate', sys.argv[1]])\n"
        "print(code, gc.isenabled(), frozen > 0, gc.get_freeze_count() == frozen)\n"
    )
    done = _python(["-c", probe, str(ONE_STEP)], tmp_path)
    assert done.stdout.split()[-4:] == ["0", "True", "True", "True"]


@pytest.mark.parametrize("user_set", [False, True])
def test_the_command_gives_its_library_settings_unless_the_user_set_them(tmp_path: Path, user_set: bool) -> None:
    """runner.cli.entry.HEADLESS: each variable is set for the command and its workers (before any library is
    imported), and one the user set, even empty, is kept as it is."""
    probe = (
        "import json, os, sys\n"
        "import runner.cli.main\n"
        "from runner.cli.entry import HEADLESS, main\n"
        "runner.cli.main.main = lambda: print(json.dumps({k: os.environ.get(k) for k in HEADLESS})) or 0\n"
        "main()\n"
        "print(json.dumps(sorted(m for m in ('numpy', 'pydantic') if m in sys.modules)))\n"
    )
    names = ("MUJOCO_GL", "OPENBLAS_THREAD_TIMEOUT", "PYDANTIC_DISABLE_PLUGINS")
    done = _python(["-c", probe], tmp_path, dict.fromkeys(names, "" if user_set else None))
    seen, imported = (json.loads(line) for line in done.stdout.splitlines()[-2:])
    assert set(seen) == set(names)
    if user_set:
        assert seen == dict.fromkeys(names, "")
    else:
        assert seen == {"MUJOCO_GL": "disable", "OPENBLAS_THREAD_TIMEOUT": "4", "PYDANTIC_DISABLE_PLUGINS": "__all__"}
    assert imported == []  # set before numpy (OpenBLAS reads it when loaded) and pydantic are imported
