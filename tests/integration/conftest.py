"""Fixtures for end-to-end runs: every scenario file, every variant, every installed backend."""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.registry import is_installed, list_backends

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "scenarios").glob("*.yaml"))


@pytest.fixture(params=[e.name for e in list_backends() if not e.opt_in])
def backend(request: pytest.FixtureRequest) -> str:
    name = request.param
    if not is_installed(name):
        pytest.skip(f"engine not installed: {name}")
    return name
