"""Determinism: per installed backend, a scenario run twice in fresh processes writes identical trace bytes.

box_pile.yaml (five boxes stacking: many contacts, the most order-sensitive of the examples) runs in two
`python -m runner` processes at once, with different string-hash seeds so that no set or dict order can leak
into the result. About 1.5 s per backend. The KUKA arm (robots/kuka_arm.yaml) does the same on PyBullet: its
scene holds the URDF's visual meshes (read by trimesh, simplified past a bound), which must come out alike.
The guarantee holds for one engine version on one platform (docs/ci.md, "Determinism")."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from backends.registry import get_backend, is_installed, list_backends
from backends.types import Capability

from .conftest import SCENARIOS


def _twice(scenario: Path, backend: str, tmp_path: Path, extra: tuple[str, ...] = ()) -> list[subprocess.Popen[str]]:
    runs = []
    for name, seed in (("a", "1"), ("b", "2")):
        cmd = [sys.executable, "-m", "runner", "run", str(scenario), "--backend", backend,
               "--out", str(tmp_path / name), "--quiet", *extra]  # fmt: skip
        env = {**os.environ, "PYTHONHASHSEED": seed}
        runs.append(subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env))
    return runs


def test_a_robot_s_visual_meshes_give_identical_traces(tmp_path: Path) -> None:
    for run in _twice(SCENARIOS / "robots" / "kuka_arm.yaml", "pybullet", tmp_path):
        out, err = run.communicate(timeout=300)
        assert run.returncode == 0, out + err
    first, second = (tmp_path / n / "kuka-arm__base__pybullet.mcap" for n in "ab")
    assert first.read_bytes() == second.read_bytes()


@pytest.mark.parametrize("backend", [e.name for e in list_backends() if not e.opt_in])
def test_fresh_processes_write_identical_traces(backend: str, tmp_path: Path) -> None:
    if not is_installed(backend):
        pytest.skip(f"engine not installed: {backend}")
    # an engine without restitution (drake) refuses the pile's bounce 0.2: the same pile without it
    plastic = () if Capability.CONTACT_BOUNCE in get_backend(backend).capabilities else ("--set", "surface.bounce=0")
    runs = _twice(SCENARIOS / "box_pile.yaml", backend, tmp_path, plastic)
    for run in runs:
        out, err = run.communicate(timeout=300)
        assert run.returncode == 0, out + err  # every assertion of the pile passed: a real, settled run
    first, second = (tmp_path / n / f"box-pile__base__{backend}.mcap" for n in "ab")
    data = first.read_bytes()
    assert len(data) > 100_000  # 601 steps of six bodies
    assert data == second.read_bytes()
