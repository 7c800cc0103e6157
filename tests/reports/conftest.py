"""Fixtures for the comparison reports: one real `scenario compare` run shared by the tests that read it.

The shared run compares factory_physics.yaml (door-stays-closed) on ode, pybullet and the crash test
backend (SIGSEGV after 30 steps), two at a time: about 4 s on an idle 2-core machine. The demo's comparison
(`make demo`: every variant on the four engines, about 15 s) and the robot arm's (kuka_arm.yaml on the four
engines, about 12 s) are shared too, for the judgement among engines.
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
KUKA = ROOT / "scenarios" / "robots" / "kuka_arm.yaml"
ENGINES = ("dart", "mujoco", "ode", "pybullet")
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


def _four_engines(tmp_path_factory: pytest.TempPathFactory, name: str, *args: str) -> CompareRun:
    for engine in ENGINES:
        if not is_installed(engine):
            pytest.skip(f"engine not installed: {engine}")
    out = tmp_path_factory.mktemp(name)
    done = scenario("compare", *args, "--backends", ",".join(ENGINES), "-j", "2", "--out", str(out))
    return CompareRun(done, out)


@pytest.fixture(scope="session")
def demo_compare(tmp_path_factory: pytest.TempPathFactory) -> CompareRun:
    """`make demo`'s comparison: factory_physics.yaml, every variant, on the four engines."""
    return _four_engines(tmp_path_factory, "demo", str(FACTORY), "--all-variants")


@pytest.fixture(scope="session")
def kuka_compare(tmp_path_factory: pytest.TempPathFactory) -> CompareRun:
    """kuka_arm.yaml on the four engines."""
    return _four_engines(tmp_path_factory, "kuka", str(KUKA))


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
