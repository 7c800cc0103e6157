"""PyBullet's inertial-to-body frame conversion (backends/pybullet/_frames.py) runs on plain floats for a few
offset bodies and on whole columns for more: both are the same operations in the same order, so they must
give the same numbers to the bit (traces do not change with the number of links), signed zeros included."""

from __future__ import annotations

import numpy as np
import pytest

from backends.registry import is_installed
from runner.compile.program import build_program
from runner.language.load import load_scenario
from tests.paths import ROOT

pytestmark = pytest.mark.skipif(not is_installed("pybullet"), reason="engine not installed: pybullet")


def test_the_column_conversion_is_the_per_body_one_to_the_bit(monkeypatch: pytest.MonkeyPatch) -> None:
    from backends.pybullet import _frames

    world = build_program(load_scenario(ROOT / "bench" / "scenarios" / "quadruped.yaml")).world
    frames = _frames.InertialFrames(world)
    assert len(frames.offsets) > _frames.PER_BODY_UP_TO  # the quadruped's legs take the column path
    rng = np.random.default_rng(29)
    rows = rng.normal(size=(len(world.bodies), 13))
    rows[:, 3:7] /= np.linalg.norm(rows[:, 3:7], axis=1, keepdims=True)  # unit quaternions (x y z w)
    first = int(next(iter(frames.offsets)))
    rows[first, :] = -0.0  # a state of signed zeros keeps its signs on both paths
    per_body, columns = rows.copy(), rows.copy()
    monkeypatch.setattr(_frames, "PER_BODY_UP_TO", len(frames.offsets))
    frames.to_body(per_body)
    monkeypatch.setattr(_frames, "PER_BODY_UP_TO", 0)
    frames.to_body(columns)
    assert not np.array_equal(per_body, rows)  # the conversion did move the offset bodies
    assert per_body.tobytes() == columns.tobytes()
