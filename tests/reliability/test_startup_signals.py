"""Signals during start-up (issue 15, item 11): a SIGTERM or Ctrl-C while the engine is imported or the world
is built is an interruption (143 / 130), never "could not import its engine".

Measured before the fix: SIGTERM during `import mujoco` gave "Backend mujoco could not import its engine...
Install it with pip install" (exit 3, no trace): the signal's KeyboardInterrupt was raised inside the
engine's pybind11 module initialisation, which turns any exception into ImportError. Now the worker holds
signals from the start of a case and raises them when the import (or the build) returns.

``slowimport`` (tests/exec/ghost/slow_engine.py) takes 2 s to import and converts exceptions as pybind11
does, so the signal lands inside the import every time; MuJoCo is then signalled at random early moments.
"""

from __future__ import annotations

import random
import signal
import time
from pathlib import Path

import pytest

from backends.registry import is_installed
from reports.trace_reader import read_trace

from .processes import start, wait_released, worker_of

DRIFT = """\
schema_version: 1
scenario: drift
world: {gravity: [0, 0, 0], dt: 0.01, duration: 50000}
bodies:
  ball: {sphere: 0.1, density: 1000, pos: [0, 0, 1], vel: [1, 0, 0]}
"""


@pytest.mark.parametrize("sig,code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)], ids=["SIGTERM", "SIGINT"])
def test_a_signal_during_the_engine_import_is_an_interruption(tmp_path: Path, sig: int, code: int) -> None:
    source = tmp_path / "drift.yaml"
    source.write_text(DRIFT)
    proc = start("run", str(source), "--backend", "slowimport", "--out", str(tmp_path / "out"))
    worker_of(proc)
    time.sleep(0.8)  # inside the 2 s import
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code, err
    assert "could not import" not in err and "Traceback" not in err
    assert ("terminated" if sig == signal.SIGTERM else "interrupted") in err
    assert not any((tmp_path / "out").iterdir())  # stopped before its trace was opened: nothing written


@pytest.mark.parametrize("trial", range(4))
def test_sigterm_early_in_a_mujoco_run_is_always_143(tmp_path: Path, trial: int) -> None:
    """At a random moment in the first 0.6 s of the worker's life: importing MuJoCo, building, or running."""
    if not is_installed("mujoco"):
        pytest.skip("engine not installed: mujoco")
    source = tmp_path / "drift.yaml"
    source.write_text(DRIFT)
    out = tmp_path / "out"
    proc = start("run", str(source), "--backend", "mujoco", "--out", str(out))
    worker_of(proc)
    time.sleep(random.Random(trial).uniform(0.0, 0.6))
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "could not import" not in err and "Traceback" not in err
    trace = out / "drift__base__mujoco.mcap"
    wait_released(trace)
    if trace.exists():  # the run had started: its trace is finished
        assert read_trace(trace).status == "interrupted"
    else:
        assert not any(out.iterdir())


def _handles_sigterm(pid: int) -> bool:
    """The process has its own SIGTERM handler (the command installs it first thing: runner.cli.entry)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) & (1 << (signal.SIGTERM - 1)))
    return False


@pytest.mark.parametrize("trial", range(6))
def test_a_signal_while_the_command_starts_is_an_interruption(tmp_path: Path, trial: int) -> None:
    """At a random moment in the first 0.4 s after the command handles signals: importing its modules
    (about 0.5 s), loading the scenario, starting its worker. (Before that the interpreter itself starts.)"""
    rng = random.Random(trial)
    sig, code = rng.choice([(signal.SIGTERM, 143), (signal.SIGINT, 130)])
    source = tmp_path / "drift.yaml"
    source.write_text(DRIFT)
    proc = start("run", str(source), "--backend", "fake", "--out", str(tmp_path / "out"))
    deadline = time.monotonic() + 30
    while not _handles_sigterm(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.002)
    time.sleep(rng.uniform(0.0, 0.4))
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code, err
    assert "Traceback" not in err and ("terminated" if sig == signal.SIGTERM else "interrupted") in err
