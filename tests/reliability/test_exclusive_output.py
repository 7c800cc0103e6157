"""Two runs into one output folder (issue 15, item 8): a run owns its output names from start to finish.

Measured before: two runs of the same scenario and variant with different parameters into the same --out:
one said "1/1 runs passed", the other "cannot rename ... .mcap.partial", and the final file failed the
mcap reader's CRC checks (3 trials of 3); once `scenario inspect` still showed it as passed. Now the
second run finds the case's lock held and fails at once with exit 2, touching nothing; the first
finishes a trace that mcap's own reader reads with CRC checks. ``FUZZ_CONCURRENT`` trials (default 5;
``make fuzz``: 20). Two runs of different cases into one folder both succeed.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

from backends.registry import is_installed
from reports.trace_reader import read_trace

from .conftest import count
from .processes import start

TRIALS = int(os.environ.get("FUZZ_CONCURRENT", "5"))
DRIFT = """\
schema_version: 1
scenario: {name}
params: {{speed: 1.0}}
world: {{gravity: [0, 0, 0], dt: 0.01, duration: 300}}
bodies:
  ball: {{sphere: 0.1, density: 1000, pos: [0, 0, 1], vel: ["${{speed}}", 0, 0]}}
assertions:
  - {{name: runs-to-the-end, at: end, check: time > 299}}
"""


def crc_checked(path: Path) -> int:
    """Messages in ``path`` read by mcap's seeking reader with every CRC checked."""
    with open(path, "rb") as f:
        return sum(1 for _ in make_reader(f, validate_crcs=True).iter_messages())


@pytest.mark.parametrize("trial", range(TRIALS))
def test_two_runs_of_the_same_case_one_wins_the_other_fails_at_once(tmp_path: Path, trial: int) -> None:
    if not is_installed("pybullet"):
        pytest.skip("engine not installed: pybullet")
    source = tmp_path / "drift.yaml"
    source.write_text(DRIFT.format(name="drift"))
    out = tmp_path / "out"
    procs = {speed: start("run", str(source), "--out", str(out), "--set", f"params.speed={speed}")
             for speed in (2.0, 3.0)}  # fmt: skip
    started = time.monotonic()
    ended: dict[float, tuple[int, str, str, float]] = {}
    for speed, proc in procs.items():
        stdout, stderr = proc.communicate(timeout=300)
        ended[speed] = (proc.returncode, stdout, stderr, time.monotonic() - started)
    codes = sorted(code for code, *_ in ended.values())
    assert codes == [0, 2], {s: (c, e[-2000:]) for s, (c, _, e, _) in ended.items()}
    (winner,) = [s for s, (c, *_) in ended.items() if c == 0]
    (loser,) = [s for s, (c, *_) in ended.items() if c == 2]
    _, _, err, _ = ended[loser]
    assert "another scenario run" in err and "is writing" in err and "Traceback" not in err
    assert "trace kept" not in err  # what it found there is the other run's
    trace = out / "drift__base__pybullet.mcap"
    assert sorted(p.name for p in out.iterdir()) == ["drift.foxglove-layout.json", "drift__base__pybullet.cost.json",
                                                     "drift__base__pybullet.mcap", "foxglove-layout.json"]  # fmt: skip
    assert crc_checked(trace) > 0
    found = read_trace(trace)
    assert found.status == "passed" and found.bodies["ball"].vel[0, 0] == winner  # the winner's run, whole
    count("concurrent runs", "one passed, the other refused (exit 2)")


def test_two_runs_of_different_cases_into_one_folder_both_succeed(tmp_path: Path) -> None:
    if not is_installed("pybullet"):
        pytest.skip("engine not installed: pybullet")
    out = tmp_path / "out"
    procs = []
    for name in ("one", "two"):
        (tmp_path / f"{name}.yaml").write_text(DRIFT.format(name=name).replace("duration: 300", "duration: 30")
                                               .replace("time > 299", "time > 29"))  # fmt: skip
        procs.append(start("run", str(tmp_path / f"{name}.yaml"), "--out", str(out)))
    for proc in procs:
        _, err = proc.communicate(timeout=300)
        assert proc.returncode == 0, err
    for name in ("one", "two"):
        assert read_trace(out / f"{name}__base__pybullet.mcap").status == "passed"
