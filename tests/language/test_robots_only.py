"""`bodies:` may be left out when robots bring every body (issue 29: it was required even then); a scenario
with neither is refused at its first line, naming `bodies`, exit 2."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from runner.language.load import load_scenario
from tests.paths import ROOT

PENDULUM = ROOT / "scenarios" / "robots" / "keyframe_pendulum.xml"


def test_a_scenario_of_robots_alone_loads(tmp_path: Path) -> None:
    shutil.copy(PENDULUM, tmp_path / PENDULUM.name)
    path = tmp_path / "s.yaml"
    path.write_text("schema_version: 1\nscenario: robots-only\nworld: {dt: 0.01, duration: 0.1}\n"
                    f"robots: {{pend: {{mjcf: {PENDULUM.name}}}}}\n")  # fmt: skip
    loaded = load_scenario(path, None)
    assert loaded.model.bodies == {} and set(loaded.robots) == {"pend"}


def test_a_scenario_without_bodies_or_robots_is_refused_by_name(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text("schema_version: 1\nscenario: nothing\nworld: {dt: 0.01, duration: 0.1}\n")
    done = subprocess.run([sys.executable, "-m", "runner", "validate", str(path)], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert f"{path}:1:1: bodies: a scenario needs at least one body" in done.stderr + done.stdout
    assert "Traceback" not in done.stderr
