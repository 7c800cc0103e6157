"""The `mujoco_warp` backend as a user runs it: a CPU run prints nothing of Warp's (its banner, its compile lines,
its native library's missing-driver warning on a machine without a GPU), and `device: cuda` on a machine whose
Warp sees no CUDA device is refused up front by name (exit 2)."""

from __future__ import annotations

import pytest

from backends.registry import is_installed
from tests.cli.test_cli import scenario
from tests.paths import ROOT

BOX_DROP = ROOT / "scenarios" / "sweeps" / "box_drop.yaml"

pytestmark = pytest.mark.skipif(not is_installed("mujoco_warp"), reason="engine not installed: mujoco_warp")


def _cuda_devices() -> int:
    from backends.mujoco_warp._backend import _quiet_warp

    return int(_quiet_warp().get_cuda_device_count())


def test_a_cpu_run_prints_only_the_runners_lines() -> None:
    done = scenario("run", str(BOX_DROP), "-b", "mujoco_warp", "--set", "world.dt=0.004", "--no-trace", "-q")
    assert done.returncode in (0, 1), done.stderr
    assert "Warp" not in done.stdout + done.stderr and "CUDA" not in done.stdout + done.stderr, done.stdout


def test_cuda_without_a_device_is_refused_before_the_run() -> None:
    if _cuda_devices():
        pytest.skip("this machine has a CUDA device: `device: cuda` runs")
    done = scenario("run", str(BOX_DROP), "-b", "mujoco_warp", "--set", "backend_options.mujoco_warp.device=cuda",
                    "--no-trace")  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    assert "cuda" in done.stderr and "Traceback" not in done.stderr
