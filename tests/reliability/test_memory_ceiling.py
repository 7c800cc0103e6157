"""The memory ceiling of a run's worker (issue 31, item 2; runner/exec/memory.py, docs/reliability.md).

A case whose worker holds more than ``SCENARIO_MEMORY_LIMIT`` (default 4096 MiB) is stopped with SIGKILL:
exit 3, ``over memory: ...`` naming the ceiling and where it comes from, the trace kept as ``.partial`` and
read by ``inspect --recover``, an outcome file saying ``over-memory``. The worker here is the test-only
``crash`` backend with ``fault: allocate``: after 3 steps it writes 2000 MiB, 64 MiB at a time, then
waits; only the ceiling ends it. The same row runs on every path in tests/exec/test_exit_codes.py.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from runner.errors import UsageError
from runner.exec import memory

from .memory import run_measured
from .processes import environment

SCENARIO = """\
schema_version: 1
scenario: hungry
world: {dt: 0.04, duration: 0.4}
bodies:
  ground: {plane: {}, motion: static}
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
backend_options:
  crash: {fault: allocate, after_steps: 3, megabytes: 2000}
"""
CEILING_MIB = 300
ASKED_MIB = 2000
#: what the worker may hold past the ceiling before it is killed: one reading every 50 ms (POLL_SECONDS),
#: during which memory written at up to 10 GB/s (one core writing pages) grows by at most 500 MB
OVERSHOOT_MIB = 512
HEADLINE = (f"over memory: the worker went over its memory ceiling of {CEILING_MIB} MiB ({memory.ENV}; "
            "docs/reliability.md); stopped by signal 9")  # fmt: skip


@pytest.mark.parametrize(("text", "expected"), [("300", 300 * memory.MIB), ("512M", 512 * memory.MIB),
                                                ("2G", 2048 * memory.MIB), ("1.5GiB", 1536 * memory.MIB),
                                                ("", memory.DEFAULT_MIB * memory.MIB), ("off", None),
                                                ("0", None)])  # fmt: skip
def test_the_ceiling_is_mebibytes_a_size_or_off(text: str, expected: int | None) -> None:
    assert memory.ceiling(text) == expected


@pytest.mark.parametrize("text", ["abc", "-5", "12T", "1e3"])
def test_a_bad_ceiling_is_refused_naming_the_variable(text: str) -> None:
    with pytest.raises(UsageError, match=f"Invalid `{memory.ENV}`"):
        memory.ceiling(text)


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_worker_over_its_ceiling_is_stopped_with_exit_3_and_a_recoverable_trace(tmp_path: Path,
                                                                                  command: str) -> None:  # fmt: skip
    source = tmp_path / "hungry.yaml"
    source.write_text(SCENARIO)
    out = tmp_path / "out"
    args = [source.as_posix(), "--backend", "crash", "--out", str(out)]
    if command == "sweep":
        args += ["--param", "world.dt=0.04"]
    env = {**environment(), memory.ENV: str(CEILING_MIB)}
    done = run_measured([command, *args], env, timeout=300, cwd=tmp_path)
    peak_mib = done.workers_mib
    assert done.code == 3, done.stdout[-2000:] + done.stderr[-2000:]
    assert HEADLINE in done.stdout + done.stderr and "Traceback" not in done.stderr
    assert CEILING_MIB < peak_mib < CEILING_MIB + OVERSHOOT_MIB < ASKED_MIB, peak_mib
    if command == "sweep":
        return
    (partial,) = out.glob("*.mcap.partial")
    (outcome,) = out.glob("*.outcome.json")
    record = json.loads(outcome.read_text())
    assert (record["outcome"], record["signal"]) == ("over-memory", 9)
    assert record["message"].splitlines()[0] == HEADLINE.removeprefix("over memory: ")
    read = subprocess.run([sys.executable, "-m", "runner", "inspect", "--recover", str(partial)], capture_output=True,
                          text=True, timeout=120, env=environment())  # fmt: skip
    assert read.returncode == 0 and "hungry" in read.stdout, read.stdout[-2000:] + read.stderr[-2000:]
