"""The pytest plugin, run in child pytest processes: items and ids, the verdict table on failure, baselines, the
collection rule that keeps a project's own tests undisturbed, and loading through the `pytest11` entry point.
Seven child processes, about 10 s in all on the shared 2-core machine (the two that run scenarios use PyBullet)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from .conftest import FACTORY
from .test_junit import DROP

PLUGIN = "runner.ci.pytest_plugin"


def pytest_run(cwd: Path, *args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    environ = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    environ.update(env or {})
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *args],
        cwd=cwd, capture_output=True, text=True, timeout=300, env=environ,
    )  # fmt: skip


def _project(tmp_path: Path) -> Path:
    """A project with its own tests (testpaths = tests, holding a scenario-like YAML fixture) and a scenario folder."""
    (tmp_path / "pytest.ini").write_text("[pytest]\ntestpaths = tests\n")
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_ok.py").write_text("def test_ok():\n    assert 1 + 1 == 2\n")
    (tmp_path / "tests" / "fixture.yaml").write_text(DROP)
    (tmp_path / "scen").mkdir()
    (tmp_path / "scen" / "drop.yaml").write_text(DROP)
    (tmp_path / "scen" / "other.yaml").write_text("name: not a scenario\non: [push]\n")  # e.g. a CI workflow
    return tmp_path


def _ids(done: subprocess.CompletedProcess[str]) -> list[str]:
    return [line for line in done.stdout.splitlines() if "::" in line]


def test_items_pass_and_a_failure_shows_the_verdict_table(tmp_path: Path) -> None:
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    scen = tmp_path / "scen"
    scen.mkdir()
    shutil.copy(FACTORY, scen / FACTORY.name)
    (scen / "drop.yaml").write_text(DROP.replace("duration: 0.4}", "duration: 0.4}\nassertions: []"))
    done = pytest_run(
        tmp_path, "-p", PLUGIN, "scen", "--scenario-backends", "pybullet", "--scenario-out", str(tmp_path / "out"),
        "-rA", "-k", "not blow-up",
    )  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr
    for variant in ("door-stays-closed", "door-opens-with-the-box-on-it", "door-moves-away-box-falls"):
        assert f"PASSED scen/factory_physics.yaml::{variant}[pybullet]" in done.stdout
    assert "PASSED scen/drop.yaml::falls[pybullet]" in done.stdout
    assert "FAILED scen/drop.yaml::wrong[pybullet]" in done.stdout
    assert "1 failed, 5 passed, 1 deselected" in done.stdout
    report = done.stdout.split("= FAILURES =")[1].split("short test summary")[0]
    assert "failed: 1 of 1 assertions: stays-up [exit 1]" in report  # `scenario run`'s first line and exit code
    assert "drop · wrong · pybullet" in report
    assert "| stays-up  | FAIL   | 1.13672  | 2 ± 0.001 | 0.400 |" in report  # measured: 2 - g dt^2 55
    assert "Traceback" not in report and "runner/" not in report and ".py:" not in report


def test_baseline_option_reports_the_first_divergence(factory_goldens: Path, tmp_path: Path) -> None:
    (tmp_path / "pytest.ini").write_text("[pytest]\nscenario_backends = pybullet\n")
    copy = tmp_path / "bouncier.yaml"
    copy.write_text(FACTORY.read_text().replace("surface: {bounce: 0.2,", "surface: {bounce: 0.5,", 1))
    done = pytest_run(
        tmp_path, "-p", PLUGIN, copy.name, "-k", "door-stays-closed", "--scenario-baseline", str(factory_goldens),
        "--scenario-out", str(tmp_path / "out"),
    )  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr
    assert "diverges from its baseline" in done.stdout
    assert "first divergence: t=1 s, body `box`, vel.z: expected " in done.stdout
    assert (tmp_path / "out" / "factory-physics__door-stays-closed__pybullet.divergence.svg").exists()
    assert "Traceback" not in done.stdout


def test_entry_point_and_the_collection_rule(tmp_path: Path) -> None:
    """Loaded through a `pytest11` entry point (a dist-info on PYTHONPATH), the plugin collects a project's
    scenario YAML only under a path named on the command line outside testpaths, or under `scenario_paths`."""
    (tmp_path / "project").mkdir()
    project = _project(tmp_path / "project")
    site = tmp_path / "site" / "scenario_plugin_probe-0.dist-info"
    site.mkdir(parents=True)
    (site / "METADATA").write_text("Metadata-Version: 2.1\nName: scenario-plugin-probe\nVersion: 0\n")
    (site / "entry_points.txt").write_text(f"[pytest11]\n{PLUGIN} = {PLUGIN}\n")
    env = {"PYTHONPATH": str(tmp_path / "site")}
    plain = ["tests/test_ok.py::test_ok"]
    scenario_ids = [f"scen/drop.yaml::{v}[fake]" for v in ("falls", "wrong", "blow-up")]
    args = ["--collect-only", "-q", "--scenario-backends", "fake"]
    assert _ids(pytest_run(project, *args, env=env)) == plain  # `pytest`: testpaths only, never YAML
    assert _ids(pytest_run(project, *args, "tests", env=env)) == plain  # named, but inside testpaths
    named = pytest_run(project, *args, "scen", env=env)
    assert _ids(named) == scenario_ids  # named outside testpaths: collected; other.yaml is no scenario
    both = pytest_run(project, "-p", PLUGIN, *args, "scen", env=env)  # entry point and -p: registered once
    assert both.returncode == 0 and _ids(both) == scenario_ids, both.stdout + both.stderr
    (project / "pytest.ini").write_text("[pytest]\ntestpaths = tests scen\nscenario_paths = scen\n")
    assert _ids(pytest_run(project, *args, env=env)) == plain + scenario_ids  # listed: collected when visited
