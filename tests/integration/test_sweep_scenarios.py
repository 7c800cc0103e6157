"""The sweep scenarios (scenarios/sweeps/) pass on every backend, at their defaults and at the corners of the
grids their headers give, or the backend refuses them up front naming the capability it lacks (drake:
`contact:bounce`). The box drop's corners: 0.1 and 10 kg, bounce 0.1 and 0.7, drop height 0.05 and 0.5 m."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from backends.errors import UnsupportedFeature
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

from .conftest import ROOT

SWEEPS = sorted((ROOT / "scenarios" / "sweeps").glob("*.yaml"))
BOX_DROP = ROOT / "scenarios" / "sweeps" / "box_drop.yaml"
CORNERS = [
    {"mass": 0.1, "bounce": 0.7, "height": 0.5},  # light, bouncy, tall: the longest bouncing
    {"mass": 10.0, "bounce": 0.1, "height": 0.05},  # heavy, dull, short: the smallest rebound
]


def _passes(path: Path, overrides: tuple[tuple[str, Any], ...], backend: str, tmp_path: Path) -> None:
    try:
        result = run_loaded(load_scenario(path, None, overrides), backend, tmp_path)
    except UnsupportedFeature as refusal:
        lacking = sorted(c.value for c in getattr(refusal, "missing", ()))
        assert lacking and all(c in str(refusal) for c in lacking) and f"`{backend}`" in str(refusal), refusal
        pytest.skip(f"refused up front by {backend}: needs {', '.join(lacking)}")
    failed = [f"{v.name}: measured {v.measured}, expected {v.expected}" for v in result.verdicts if not v.passed]
    assert result.status == "passed", f"{result.failure or ''}\n" + "\n".join(failed)
    assert result.verdicts


@pytest.mark.parametrize("path", SWEEPS, ids=[p.stem for p in SWEEPS])
def test_sweep_scenario_passes_at_its_defaults(path: Path, backend: str, tmp_path: Path) -> None:
    _passes(path, (), backend, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("corner", CORNERS, ids=["light-bouncy-tall", "heavy-dull-short"])
def test_box_drop_passes_at_the_corners_of_its_grid(corner: dict[str, float], backend: str, tmp_path: Path) -> None:
    _passes(BOX_DROP, tuple((f"params.{k}", v) for k, v in corner.items()), backend, tmp_path)
