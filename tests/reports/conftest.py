"""Fixtures for the comparison reports: one real `scenario compare` run shared by the tests that read it.

The shared run compares factory_physics.yaml (door-stays-closed) on ode, pybullet and the crash test
backend (SIGSEGV after 30 steps), two at a time: about 4 s on an idle 2-core machine.
"""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from backends.registry import is_installed

ROOT = Path(__file__).resolve().parents[2]
FACTORY = ROOT / "scenarios" / "factory_physics.yaml"
INTERVALS = ROOT / "scenarios" / "factory_intervals.yaml"
CLI = [sys.executable, "-m", "runner"]


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slow: takes more than a few seconds (its docstring says how long)")


def scenario(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, cwd=cwd, timeout=600)


@dataclass
class CompareRun:
    done: subprocess.CompletedProcess[str]
    out: Path

    @property
    def traces(self) -> Path:
        return self.out / "traces"

    @property
    def doc(self) -> dict[str, Any]:
        return json.loads((self.out / "report.json").read_text(encoding="utf-8"))

    def run(self, backend: str) -> dict[str, Any]:
        return next(r for r in self.doc["cases"][0]["runs"] if r["backend"] == backend)


@pytest.fixture(scope="session")
def compare_run(tmp_path_factory: pytest.TempPathFactory) -> CompareRun:
    for name in ("ode", "pybullet"):
        if not is_installed(name):
            pytest.skip(f"engine not installed: {name}")
    out = tmp_path_factory.mktemp("compare")
    done = scenario(
        "compare", str(FACTORY), "--variant", "door-stays-closed", "--backends", "ode,pybullet,crash",
        "-j", "2", "--timeout", "300", "--out", str(out),
    )  # fmt: skip
    return CompareRun(done, out)


@dataclass
class SoundReport:
    out: Path
    traces: Path


@pytest.fixture(scope="session")
def sound_report(tmp_path_factory: pytest.TempPathFactory) -> SoundReport:
    """factory_intervals (door-closed: the box hits the door, thud.wav plays) on fake and ode, in process:
    about 1 s. Every body is kinematic, so the two runs are identical."""
    from reports.build import write_report
    from runner.language.load import load_scenario
    from runner.sim.run import run_loaded

    if not is_installed("ode"):
        pytest.skip("engine not installed: ode")
    out = tmp_path_factory.mktemp("sounds")
    case = load_scenario(INTERVALS, "door-closed")
    for backend in ("fake", "ode"):
        run_loaded(case, backend, out / "traces")
    write_report([out / "traces"], out)
    return SoundReport(out, out / "traces")
