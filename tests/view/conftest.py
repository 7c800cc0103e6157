"""Helpers of the `scenario view` tests: the command in a child process (Panda3D has one window per
process), a virtual X display, and comparing two traces through reports.trace_reader."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from reports.trace_reader import Trace

ROOT = Path(__file__).resolve().parents[2]
FACTORY = ROOT / "scenarios" / "factory_physics.yaml"
CLI = [sys.executable, "-m", "runner"]
REQUIRE_XVFB = os.environ.get("SCENARIO_REQUIRE_XVFB") == "1"


def scenario(*args: str, env: dict[str, str] | None = None, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, cwd=ROOT, timeout=timeout, env=env)


def quiet_env(**extra: str) -> dict[str, str]:
    """The environment of a child: OpenAL's null device (no sound card on a server), plus ``extra``."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["ALSOFT_DRIVERS"] = "null"
    env.update(extra)
    return env


def copy_scenario(src: Path, folder: Path) -> Path:
    """A copy of ``src`` (and the sounds beside it) to record into: the committed file is never touched."""
    target = folder / src.name
    shutil.copy(src, target)
    if (src.parent / "sounds").is_dir():
        shutil.copytree(src.parent / "sounds", folder / "sounds", dirs_exist_ok=True)
    return target


def need_panda3d() -> None:
    pytest.importorskip("panda3d.core", reason="engine not installed: panda3d (the view extra)")


@pytest.fixture(scope="session")
def xdisplay(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A virtual X display (Xvfb, 1280 x 800, 24 bit) for the session; skipped without Xvfb and xdotool
    unless SCENARIO_REQUIRE_XVFB=1 (CI), where their absence fails."""
    need_panda3d()
    missing = [tool for tool in ("Xvfb", "xdotool") if shutil.which(tool) is None]
    if missing:
        message = f"tool not installed: {', '.join(missing)} (Debian packages xvfb, xdotool)"
        if REQUIRE_XVFB:
            pytest.fail(message)
        pytest.skip(message)
    read, write = os.pipe()
    log = (tmp_path_factory.mktemp("xvfb") / "xvfb.log").open("w")
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
                            pass_fds=(write,), stdout=log, stderr=log)  # fmt: skip
    os.close(write)
    number = b""
    deadline = time.monotonic() + 30
    while not number.endswith(b"\n") and time.monotonic() < deadline:
        chunk = os.read(read, 16)
        if not chunk:
            break
        number += chunk
    os.close(read)
    if not number.strip():
        proc.kill()
        pytest.fail("Xvfb did not start")
    try:
        yield f":{number.decode().strip()}"
    finally:
        proc.terminate()
        proc.wait(timeout=10)
        log.close()


def assert_same_run(a: Trace, b: Trace) -> None:
    """Every recorded step's state, every event, sound and verdict the same (exactly)."""
    assert np.array_equal(a.times, b.times)
    assert a.bodies.keys() == b.bodies.keys()
    for name in a.bodies:
        for field in ("pos", "quat", "vel", "angvel"):
            assert np.array_equal(getattr(a.bodies[name], field), getattr(b.bodies[name], field)), (name, field)
    for name in a.joints:
        for field in ("position", "velocity", "motor_force"):
            assert np.array_equal(getattr(a.joints[name], field), getattr(b.joints[name], field)), (name, field)
    assert a.state == b.state
    assert a.contacts == b.contacts
    assert [(e.t, e.name, e.source) for e in a.events] == [(e.t, e.name, e.source) for e in b.events]
    assert [(s.t, s.name, s.action) for s in a.sounds] == [(s.t, s.name, s.action) for s in b.sounds]
    assert [v.data for v in a.verdicts] == [v.data for v in b.verdicts]
    assert a.status == b.status
