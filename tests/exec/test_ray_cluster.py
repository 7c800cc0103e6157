"""Scale-out on a real two-node Ray cluster (tests/exec/cluster.py): a sweep of 100 cases whose traces
come back to the driver, one Ray worker of the second node killed mid-sweep (its case is submitted once
more: runner.exec.remote), every trace byte for byte the one a local sweep writes; then Ctrl-C mid-sweep
cancels what is in flight and leaves every finished trace.

The driver is `scenario sweep --executor ray` in a process of its own (tests/exec/ray_driver.py, which
kills the worker, or sends itself SIGINT, from the results as they come back: no timed waits). The cases
are 0.1 s columns of 1 to 4 boxes on PyBullet (10 steps). About 35 s on the two-core machine, 90 s under
heavy load. Skipped only when the `ray` extra is not
installed, and never in CI (`SCENARIO_REQUIRE_RAY=1`, set by .ci/run, makes a missing Ray a failure).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from reports.trace_reader import read_trace

if os.environ.get("SCENARIO_REQUIRE_RAY") != "1":
    pytest.importorskip("ray", reason="the `ray` extra is not installed: pip install 'physics-scenarios[ray]'")

from runner.cli.main import main  # noqa: E402

from .cluster import Cluster  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
PILE = ROOT / "scenarios" / "box_pile.yaml"
DENSITIES = ",".join(str(100 * k) for k in range(1, 26))  # x 4 counts = 100 cases


@pytest.fixture(scope="module")
def cluster() -> Iterator[Cluster]:
    c = Cluster()
    try:
        start = time.monotonic()
        c.start()
        c.wait_for_nodes()
        print(f"two-node Ray cluster up in {time.monotonic() - start:.1f} s")
        yield c
    finally:
        left = c.stop()
        assert not left, f"processes of the test cluster still running: {left}"


def sweep_args(out: Path, counts: str = "1,2,3,4", densities: str = DENSITIES) -> list[str]:
    return ["sweep", str(PILE), "--param", f"count={counts}", "--param", f"bodies.crate.density={densities}",
            "--backend", "pybullet", "--set", "world.duration=0.1", "--metric", "max(crate.pos.z)",
            "--out", str(out), "-q"]  # fmt: skip


def drive(cluster: Cluster, mode: str, after: int, marker: str, argv: list[str]) -> dict[str, Any]:
    cmd = [sys.executable, "-m", "tests.exec.ray_driver", mode, str(after), marker, "--", *argv,
           "--executor", "ray", "--ray-address", cluster.address]  # fmt: skip
    done = subprocess.run(cmd, cwd=ROOT, env=cluster.env, capture_output=True, text=True, timeout=600)
    assert done.stdout.strip(), done.stderr[-3000:]
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def same_files(a: Path, b: Path, pattern: str) -> list[Path]:
    names = sorted(p.relative_to(a) for p in a.rglob(pattern))
    assert sorted(p.relative_to(b) for p in b.rglob(pattern)) == names
    for rel in names:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    return names


@pytest.mark.slow
def test_a_sweep_on_two_nodes_survives_a_lost_worker_and_equals_the_local_sweep(
    cluster: Cluster, tmp_path: Path
) -> None:
    remote = drive(cluster, "kill", 10, cluster.nodes[1].marker, sweep_args(tmp_path / "ray"))
    assert main([*sweep_args(tmp_path / "local"), "-j", "2"]) == remote["code"]
    assert remote["killed"], "no Ray worker of the second node was running a case after the first results"
    assert len(remote["retried"]) == 1  # the killed worker's case, submitted once more
    for name in ("sweep.json", "sweep.csv", "sweep.svg"):
        assert (tmp_path / "ray" / name).read_bytes() == (tmp_path / "local" / name).read_bytes(), name
    assert len(same_files(tmp_path / "ray", tmp_path / "local", "*.mcap")) == 100
    assert not list((tmp_path / "ray").rglob("*.partial")) and not list((tmp_path / "ray").rglob("*.outcome.json"))
    print(f"100 cases on the two-node cluster: {remote['seconds']:.1f} s")


@pytest.mark.slow
def test_ctrl_c_on_ray_cancels_the_tasks_in_flight_and_keeps_every_finished_trace(
    cluster: Cluster, tmp_path: Path
) -> None:
    argv = sweep_args(tmp_path / "ray", "2,3", "100,200,300,400,500,600")  # 12 cases
    remote = drive(cluster, "interrupt", 3, "-", [*argv, "-j", "2"])
    assert remote["code"] == 130
    finished = {int(k) for k, status in remote["seen"].items() if status in ("passed", "failed")}
    assert len(finished) >= 3 and len(remote["seen"]) == len(finished)  # Ray cases are never half-returned
    local = tmp_path / "local"
    assert main([*sweep_args(local, "2,3", "100,200,300,400,500,600"), "-j", "2"]) in (0, 1)
    traces = sorted((tmp_path / "ray" / "traces").glob("*/*.mcap"))
    assert len(traces) == len(finished) and not list((tmp_path / "ray").rglob("*.partial"))
    for trace in traces:  # each finished case's whole trace, byte for byte the local one
        assert int(trace.parent.name[:3]) in finished
        assert trace.read_bytes() == (local / trace.relative_to(tmp_path / "ray")).read_bytes()
        assert read_trace(trace).status in ("passed", "failed")
    # the cancelled tasks' Ray workers were killed: no worker of either node still runs a case
    deadline = time.monotonic() + 30
    while any(n.workers_running("ray_task") for n in cluster.nodes) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(n.workers_running("ray_task") for n in cluster.nodes)
