"""Every scenario in scenarios/ runs on every backend, passes, and its trace says what happened; or the backend
refuses it up front naming the capability it lacks (drake: `contact:bounce`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backends.errors import UnsupportedFeature
from reports.trace_reader import read_trace
from runner.language.load import load_scenario, variant_names
from runner.sim.run import RunResult, run_loaded

from .conftest import ROOT, SCENARIOS

CASES = [(p, v) for p in SCENARIOS for v in variant_names(p)]


def _run_loaded(path: Path, variant: str | None, backend: str, tmp_path: Path) -> RunResult:
    """``run_loaded``, or a skip when the backend refuses the case up front: the refusal names the
    capability and the backend (exit 2 on the command line)."""
    try:
        return run_loaded(load_scenario(path, variant), backend, tmp_path)
    except UnsupportedFeature as refusal:
        lacking = sorted(c.value for c in getattr(refusal, "missing", ()))
        assert lacking and all(c in str(refusal) for c in lacking) and f"`{backend}`" in str(refusal), refusal
        pytest.skip(f"refused up front by {backend}: needs {', '.join(lacking)}")


@pytest.mark.parametrize("path,variant", CASES, ids=[f"{p.stem}:{v}" for p, v in CASES])
def test_scenario_passes(path: Path, variant: str, backend: str, tmp_path: Path) -> None:
    result = _run_loaded(path, variant, backend, tmp_path)
    failed = [
        f"{v.name}: measured {v.measured}, expected {v.expected} {v.message}" for v in result.verdicts if not v.passed
    ]
    assert result.status == "passed", f"{result.failure or ''}\n" + "\n".join(failed)
    assert result.verdicts, "a scenario case without assertions checks nothing"
    trace = read_trace(Path(result.trace))
    assert trace.complete and trace.metadata["result"]["status"] == "passed"


def _run(tmp_path: Path, name: str, variant: str, backend: str):  # noqa: ANN202
    result = _run_loaded(ROOT / "scenarios" / name, variant, backend, tmp_path)
    return result, read_trace(Path(result.trace))


def test_closed_door_box_stops_at_the_touch_height(tmp_path: Path, backend: str) -> None:
    """Acceptance: z stops within two steps of motion of the sphere-polygon touch height; one event."""
    _, trace = _run(tmp_path, "factory_intervals.yaml", "door-closed", backend)
    z = trace.bodies["box"].pos[:, 2]
    touch = 1.5 * 0.3  # sphere radius after the box's scale, above the door's plane z = 0
    speed = 1.0 / 1.0 * 0.04  # the drop moves 1 m/s: 0.04 m per step
    assert touch - 2 * speed <= z[-1] <= touch
    assert np.all(z[np.searchsorted(trace.times, 2.16) :] == z[-1])  # it stopped and stayed
    hits = [e for e in trace.events if e.name == "box-into-door"]
    assert len(hits) == 1 and hits[0].t == pytest.approx(2.16)
    assert [s.t for s in trace.sounds if s.name == "thud" and s.action == "start"] == [pytest.approx(2.16)]


def test_lab_kick_velocities_from_the_trace(tmp_path: Path, backend: str) -> None:
    """The one-step 1000 N kick: v1 = 1000*0.04/13.5 - 9.81*0.04, v2 = v1 - 9.81*0.04 (ODE's addForce)."""
    _, trace = _run(tmp_path, "factory_physics.yaml", "door-stays-closed", backend)
    vz = trace.bodies["box"].vel[:, 2]
    v1 = 1000 * 0.04 / 13.5 - 9.81 * 0.04
    assert trace.times[1] == pytest.approx(0.04) and trace.times[2] == pytest.approx(0.08)
    assert vz[1] == pytest.approx(v1, abs=1e-4)
    assert vz[2] == pytest.approx(v1 - 9.81 * 0.04, abs=1e-4)


def test_door_acceleration_is_fmax_over_m(tmp_path: Path, backend: str) -> None:
    _, trace = _run(tmp_path, "factory_physics.yaml", "door-opens-with-the-box-on-it", backend)
    t, vx = trace.times, trace.bodies["door"].vel[:, 0]
    window = (t > 3.05) & (t < 4.2)  # accelerating: from the press at 3.0 to 0.3 m/s at 3 + 1.24
    slope = np.polyfit(t[window], vx[window], 1)[0]
    assert slope == pytest.approx(100 / 413.5, rel=0.01)
