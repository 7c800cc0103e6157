"""A bug in this tool (issue 14): "internal error, please report", exit 70, on every path; its traceback only
with SCENARIO_DEBUG=1, where it is shown whichever process met it.

The bug: the test-only `buggy` adapter (tests/exec/ghost/buggy_engine.py) raises TypeError at its third
step. It crosses from the worker with its class name and traceback, and is never "engine failure".
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.exec.exit_table import environment

SOURCE = """\
schema_version: 1
scenario: bug
world: {dt: 0.01, duration: 0.1}
bodies:
  ball: {sphere: 0.1, density: 1000, pos: [0, 0, 1]}
"""
FIRST = "internal error, please report: TypeError: unsupported operand type(s) for +: 'float' and 'NoneType'"


def scenario(tmp_path: Path, *args: str, debug: str = "0") -> subprocess.CompletedProcess[str]:
    (tmp_path / "bug.yaml").write_text(SOURCE)
    env = {**environment(), "SCENARIO_DEBUG": debug}
    return subprocess.run([sys.executable, "-m", "runner", *args], capture_output=True, text=True, timeout=300,
                          cwd=tmp_path, env=env)  # fmt: skip


@pytest.mark.parametrize("path", [[], ["-j", "2"], ["--isolate"], ["--trace-process"]],
                         ids=["serial", "-j 2", "--isolate", "--trace-process"])  # fmt: skip
def test_a_bug_is_exit_70_internal_error_please_report(tmp_path: Path, path: list[str]) -> None:
    done = scenario(tmp_path, "run", "bug.yaml", "--backend", "buggy", "--out", "out", *path)
    assert done.returncode == 70, done.stdout + done.stderr
    assert done.stderr.splitlines()[0] == FIRST
    assert f"bug · base · buggy: {FIRST}" in done.stdout
    assert "Traceback" not in done.stderr and "engine failure" not in done.stdout + done.stderr


def test_with_scenario_debug_the_traceback_of_the_worker_is_shown(tmp_path: Path) -> None:
    done = scenario(tmp_path, "run", "bug.yaml", "--backend", "buggy", "--out", "out", debug="1")
    assert done.returncode == 70
    assert "Traceback (most recent call last)" in done.stderr and 'buggy_engine.py", line' in done.stderr


def test_compare_shows_the_same_row(tmp_path: Path) -> None:
    done = scenario(tmp_path, "compare", "bug.yaml", "--backends", "buggy", "--out", "cmp")
    assert done.returncode == 1, done.stdout + done.stderr
    assert f"      {FIRST} [exit 70]" in done.stdout
