"""A full disk or a write refused while the trace is written (issue 15, item 6): exit 74 ("output error")
on every path, the trace kept as a .partial that `inspect --recover` reads to its last byte, and no
temporary file left behind.

Measured before: a traceback and exit 1 serially, exit 3 with -j 2, exit 2 with --trace-process, a stray
`outcome.json.tmp` and an unreadable tail in the .partial. The disk: a 32 KiB tmpfs mounted as the output
folder (root), and a 32 KiB file-size limit (RLIMIT_FSIZE: EFBIG, any user); the scenario's trace is
about 63 KiB (half of it fits). The exit codes and first lines on every path, Ray and compare included, are in
tests/exec/test_exit_codes.py.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from backends.registry import is_installed
from reports.trace_reader import read_trace
from tests.exec.exit_table import ROOT, _limits, environment, output_folder

from .test_interruptions import complete_record_end

FACTORY = ROOT / "scenarios" / "factory_physics.yaml"
TRACE = "factory-physics__door-stays-closed__pybullet.mcap"
DISKS = ["tmpfs", "file-size limit"] if os.geteuid() == 0 else ["file-size limit"]


@pytest.mark.parametrize("disk", DISKS)
@pytest.mark.parametrize("path", [[], ["-j", "2"], ["--isolate"], ["--trace-process"]],
                         ids=["serial", "-j 2", "--isolate", "--trace-process"])  # fmt: skip
def test_a_full_disk_is_exit_74_and_keeps_a_readable_partial(tmp_path: Path, disk: str, path: list[str]) -> None:
    if not is_installed("pybullet"):
        pytest.skip("engine not installed: pybullet")
    with output_folder(tmp_path, disk == "tmpfs") as (out, limits):
        if disk != "tmpfs":
            limits["fsize"] = 32 * 1024
        done = subprocess.run([sys.executable, "-m", "runner", "run", str(FACTORY), "--out", str(out), *path],
                              capture_output=True, text=True, timeout=300, env=environment(),
                              preexec_fn=lambda: _limits(limits))  # fmt: skip
        assert done.returncode == 74, done.stdout + done.stderr
        assert "Traceback" not in done.stderr
        reason = "No space left on device" if disk == "tmpfs" else "File too large"
        assert f"output error: cannot write trace {out}/{TRACE}.partial: {reason}" in done.stderr
        left = sorted(p.name for p in out.iterdir() if not p.name.endswith("foxglove-layout.json"))  # 4 KB: may fit
        assert left in ([f"{TRACE}.partial"], [f"{TRACE}.partial", TRACE.replace(".mcap", ".outcome.json")]), left
        partial = out / f"{TRACE}.partial"
        assert complete_record_end(partial) == partial.stat().st_size  # cut back to the last whole record
        trace = read_trace(partial, recover=True)  # cut mid-run, or (the limit) only its closing summary lost
        assert trace.status in ("incomplete", "passed") and trace.scenario["backend"] == "pybullet"
        assert trace.times[0] == 0 and len(trace.times) > 1
        inspect = subprocess.run([sys.executable, "-m", "runner", "inspect", "--recover", str(partial)],
                                 capture_output=True, text=True, timeout=120)  # fmt: skip
        assert inspect.returncode == 0 and "factory-physics" in inspect.stdout, inspect.stderr


@pytest.mark.parametrize("path", [[], ["-j", "2"], ["--trace-process"]], ids=["serial", "-j 2", "--trace-process"])
def test_a_case_started_on_a_full_disk_leaves_no_empty_partial(tmp_path: Path, path: list[str]) -> None:
    """A case whose trace could not take even its header (the disk filled before it started) left a 0-byte
    `.partial` that `inspect --recover` cannot read, and was announced as "trace kept". A file-size limit of
    8 bytes (any user) lets the trace's magic in and refuses its first record."""
    scenario = tmp_path / "fall.yaml"
    scenario.write_text("schema_version: 1\nscenario: fall\nworld: {dt: 0.01, duration: 0.1}\nbodies:\n"
                        "  ball: {sphere: 0.1, mass: 1, pos: [0, 0, 1]}\n")  # fmt: skip
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "runner", "run", str(scenario), "--backend", "fake", "--out",
                           str(out), *path], capture_output=True, text=True, timeout=300, env=environment(),
                          preexec_fn=lambda: _limits({"fsize": 8}))  # fmt: skip
    assert done.returncode == 74, done.stdout + done.stderr
    assert f"output error: cannot write trace {out}/fall__base__fake.mcap.partial: File too large" in done.stderr
    assert "trace kept" not in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert not [p.name for p in out.iterdir() if p.name.endswith(".partial")]
