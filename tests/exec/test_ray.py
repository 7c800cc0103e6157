"""A sweep through Ray gives what it gives locally: the same table and the same traces, byte for byte.

Starts a local Ray instance (2 CPUs), so it is slow: about 20 s here, most of it Ray starting. Skipped,
with the reason, only when the `ray` extra is not installed, and never in CI (SCENARIO_REQUIRE_RAY=1).
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest

from runner.cli.main import main

if os.environ.get("SCENARIO_REQUIRE_RAY") != "1":  # CI (.ci/run) requires Ray
    pytest.importorskip("ray", reason="the `ray` extra is not installed: pip install 'physics-scenarios[ray]'")

from runner.exec.executors import Case, RayExecutor  # noqa: E402 - after the skip

ROOT = Path(__file__).resolve().parents[2]
PILE = ROOT / "scenarios" / "box_pile.yaml"


def sweep(out: Path, *extra: str) -> int:
    return main([
        "sweep", str(PILE), "--param", "count=2,3", "--param", "world.dt=0.01,0.02", "--backends", "pybullet",
        "--set", "world.duration=0.4", "--metric", "max(crate.pos.z)", "--out", str(out), "-q", *extra,
    ])  # fmt: skip


@pytest.mark.slow
def test_sweep_through_ray_equals_the_local_sweep(tmp_path: Path) -> None:
    local = tmp_path / "local"
    remote = tmp_path / "ray"
    assert sweep(local, "-j", "2") == 1  # the 0.4 s piles do not settle: pile-settles fails, exit 1
    assert sweep(remote, "--executor", "ray", "-j", "2") == 1
    assert (remote / "sweep.json").read_text() == (local / "sweep.json").read_text()
    assert (remote / "sweep.csv").read_text() == (local / "sweep.csv").read_text()
    assert (remote / "sweep.svg").read_text() == (local / "sweep.svg").read_text()
    traces = sorted(p.relative_to(local) for p in local.rglob("*.mcap"))
    assert len(traces) == 4
    for rel in traces:
        assert (remote / rel).read_bytes() == (local / rel).read_bytes()
    # the table is physics: each pile's top box sits 0.3 m per box above the lowest one's centre
    rows = list(csv.DictReader((local / "sweep.csv").read_text().splitlines()))
    assert len(rows) == 4
    for row in rows:
        count, top = int(row["params.count"]), float(row["max(crate.pos.z)"])
        assert top == pytest.approx(0.15 + 0.3 * (count - 1), abs=0.01 * count)


@pytest.mark.slow
def test_ray_reports_errors_and_crashes_as_results(tmp_path: Path) -> None:
    executor = RayExecutor(None, 2)
    try:
        results = executor.run([
            Case(str(PILE), None, "nope", (("world.duration", 0.1),), None),
            Case(str(PILE), None, "crash", (("world.duration", 0.5), ("backend_options.crash.after_steps", 2)), None),
            Case(str(PILE), None, "pybullet", (("world.duration", 0.1),), str(tmp_path)),
        ])  # fmt: skip
    finally:
        executor.close()
    assert [r.status for r in results] == ["error", "crashed", "failed"]
    assert results[0].error_type == "UnknownBackend"
    assert Path(results[2].result.trace).parent == tmp_path  # the trace came back from the worker
    assert Path(results[2].result.trace).is_file()
