"""Helpers for the tests that run `scenario` as a user does and act on its processes."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from tests.exec.exit_table import environment

__all__ = ["CLI", "environment", "start", "wait_released", "worker_of"]

CLI = [sys.executable, "-m", "runner"]


def start(*args: str, cwd: Path | None = None) -> subprocess.Popen[str]:
    """``scenario ARGS`` with the test-only backends registered (tests/exec/ghost)."""
    return subprocess.Popen([*CLI, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=environment(), cwd=cwd)  # fmt: skip


def worker_of(child: subprocess.Popen[str], timeout: float = 30.0) -> int:
    """The pid of the worker process running the case (the command's child: the CLI forks its workers)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = Path(f"/proc/{child.pid}/task/{child.pid}/children").read_text().split()
        if found:
            return int(found[0])
        if child.poll() is not None:
            break
        time.sleep(0.01)
    raise AssertionError(f"no worker process (the command ended with {child.returncode})")


def wait_released(trace: Path, timeout: float = 30.0) -> None:
    """Until no process owns the case's output names (its worker has ended and removed its lock file)."""
    lock = trace.with_name(f".{trace.name}.lock")
    deadline = time.monotonic() + timeout
    while lock.exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not lock.exists(), f"{lock} still held after {timeout} s"
