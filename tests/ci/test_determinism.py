"""Determinism: per installed backend, a scenario run twice in fresh processes writes identical trace bytes.

box_pile.yaml (five boxes stacking: many contacts, the most order-sensitive of the examples) runs in two
`python -m runner` processes at once, with different string-hash seeds so that no set or dict order can leak
into the result. About 1.5 s per backend. The guarantee holds for one engine version on one platform
(docs/ci.md, "Determinism")."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from backends.registry import is_installed, list_backends

from .conftest import SCENARIOS


@pytest.mark.parametrize("backend", [e.name for e in list_backends()])
def test_fresh_processes_write_identical_traces(backend: str, tmp_path: Path) -> None:
    if not is_installed(backend):
        pytest.skip(f"engine not installed: {backend}")
    runs = []
    for name, seed in (("a", "1"), ("b", "2")):
        cmd = [sys.executable, "-m", "runner", "run", str(SCENARIOS / "box_pile.yaml"), "--backend", backend,
               "--out", str(tmp_path / name), "--quiet"]  # fmt: skip
        env = {**os.environ, "PYTHONHASHSEED": seed}
        runs.append(subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env))
    for run in runs:
        out, err = run.communicate(timeout=300)
        assert run.returncode == 0, out + err  # every assertion of the pile passed: a real, settled run
    first, second = (tmp_path / n / f"box-pile__base__{backend}.mcap" for n in "ab")
    data = first.read_bytes()
    assert len(data) > 100_000  # 601 steps of six bodies
    assert data == second.read_bytes()
