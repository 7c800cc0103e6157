"""Every engine that batches worlds (``Backend.world_batch()`` is not None) runs the box drop's 256-variant grid
(8 masses x 4 bounces x 8 drop heights, scenarios/sweeps/box_drop.yaml) as one batch with the same verdicts as
256 separate runs on the same backend: the same sweep.csv (statuses and every assertion's pass/FAIL per case).

The engines come from the registry, hidden test backends included (the fake backend's batch), so an engine that
gains a batch joins here without editing this test; one without a batch is skipped by name (its sweeps run
separately: the fallback is checked in test_batched_sweep.py). The grid runs at dt 4 ms (500 steps of the 2 s
drop; the scenario's tolerances scale with dt) so that the separate runs stay short on a CPU.

A real engine's separate runs each start a process that loads the engine (MuJoCo Warp: about 6 s of CPU each,
25 min for 256 on this 2-core machine), so on a real engine CI runs the grid's corners and middle (2 masses x
2 bounces x 4 heights: 16 variants, the extremes of each parameter); the full 256-variant comparison on
mujoco_warp is `bench/sweep_batch.sh`, its result in bench/results.md (section 12)."""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.registry import get_backend, is_installed, list_backends
from runner.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
BOX_DROP = ROOT / "scenarios" / "sweeps" / "box_drop.yaml"
GRID = ["--param", "mass=0.1,0.2,0.5,1,2,4,7,10", "--param", "bounce=0.1,0.3,0.5,0.7",
        "--param", "height=0.05,0.1,0.15,0.2,0.25,0.3,0.4,0.5", "--set", "world.dt=0.004"]  # fmt: skip
#: installed engines, the test backends included, but the one that kills its own process
ENGINES = [e.name for e in list_backends(include_hidden=True) if e.name != "crash" and is_installed(e.name)]
#: 8 variants: each parameter's extremes
CORNERS = ["--param", "mass=0.1,10", "--param", "bounce=0.1,0.7", "--param", "height=0.05,0.5",
           "--set", "world.dt=0.004"]  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("backend", ENGINES)
def test_a_batched_grid_has_the_verdicts_of_separate_runs(backend: str, tmp_path: Path) -> None:
    if get_backend(backend).world_batch() is None:
        pytest.skip(f"{backend} does not batch worlds")
    grid, cases = (GRID, 256) if backend == "fake" else (CORNERS, 8)
    common = ["sweep", str(BOX_DROP), *grid, "-b", backend, "-q", "--force"]
    alone = main([*common, "--out", str(tmp_path / "alone")])
    batched = main([*common, "--out", str(tmp_path / "batch"), "--batch", "--traces"])
    assert batched == alone
    table = (tmp_path / "alone" / "sweep.csv").read_text()
    assert table.count("\n") == cases + 1  # the header and the cases
    assert (tmp_path / "batch" / "sweep.csv").read_text() == table
