"""Benchmark 9: scale-out on a real two-node Ray cluster, measured by running its test.

``tests/exec/test_ray_cluster.py`` in a child pytest (``SCENARIO_REQUIRE_RAY=1``): two ``ray start`` nodes
on this machine with their own temporary folders, a 100-case sweep whose traces come back to the driver
while one Ray worker of the second node is killed (its case retried once), every trace compared byte for
byte with the same sweep run locally, then Ctrl-C mid-sweep. The figures are the test's own prints (the
cluster's start-up, the 100-case sweep on the cluster) and the whole module's wall time.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).parent.parent
TEST = "tests/exec/test_ray_cluster.py"


@dataclass(frozen=True)
class RayFigures:
    passed: bool
    summary: str  # pytest's last line
    startup: float | None  # seconds for the two nodes to be up
    sweep: float | None  # seconds for the 100 cases on the cluster
    wall: float  # the whole test module, pytest start-up included


def run(log: Callable[[str], None] = print) -> RayFigures:
    env = {**os.environ, "SCENARIO_REQUIRE_RAY": "1"}
    start = time.perf_counter()
    cmd = [sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:cacheprovider", TEST]
    try:
        done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=1200, check=False)
        text, ok = done.stdout + done.stderr, done.returncode == 0
    except subprocess.TimeoutExpired as exc:
        out = exc.stdout.decode(errors="replace") if isinstance(exc.stdout, bytes) else exc.stdout or ""
        text, ok = f"{out}\nnot done within 1200 s", False
    wall = time.perf_counter() - start
    up = re.search(r"cluster up in ([0-9.]+) s", text)
    sweep = re.search(r"100 cases on the two-node cluster: ([0-9.]+) s", text)
    lines = [x for x in text.strip().splitlines() if x.strip()]
    fig = RayFigures(ok, lines[-1].strip("= ") if lines else "", float(up.group(1)) if up else None,
                     float(sweep.group(1)) if sweep else None, wall)  # fmt: skip
    log(f"  ray: {'passed' if ok else 'FAILED'} in {wall:.0f} s ({fig.summary})")
    return fig


def targets(fig: RayFigures | None) -> list[str]:
    if fig is None:
        return []
    detail = (f"cluster up in {fig.startup:.0f} s, 100 cases on it in {fig.sweep:.0f} s, the module {fig.wall:.0f} s"
              if fig.startup is not None and fig.sweep is not None else fig.summary)  # fmt: skip
    return [f"| scale-out on a two-node Ray cluster: 100-case sweep, a worker killed (its case retried once), "
            f"traces byte for byte the local ones; Ctrl-C keeps the finished traces ({TEST}) | {detail} "
            f"| {'met' if fig.passed else '**not met**'} | {'' if fig.passed else fig.summary} |"]  # fmt: skip
