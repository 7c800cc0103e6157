"""The bench's robot section: an engine that refuses the arm is reported with its refusal (the pure-Python
backend, which declares no robot capability), and the measuring path (build, engine and runner milliseconds
per step) gives figures for a real engine that runs the arm (PyBullet, a base dependency)."""

from __future__ import annotations

import json

import pytest

from bench import robot


def test_a_refusing_engine_is_reported_with_its_refusal(capsys: pytest.CaptureFixture[str]) -> None:
    assert robot._child(["fake", "kuka arm", "1"]) == 0
    fig = robot.RobotFigures(**json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    assert fig.build_s is None and fig.robot == "kuka arm"
    assert fig.note.startswith("refused up front: needs ") and "shape:compound" in fig.note
    assert f"| fake | kuka arm | | | | | | | | | {fig.note} |" in robot.render([fig])


@pytest.mark.slow
def test_the_measuring_path(capsys: pytest.CaptureFixture[str]) -> None:
    from backends.pybullet import PyBulletBackend

    step, init = PyBulletBackend._step, PyBulletBackend.__init__
    assert robot._child(["pybullet", "kuka arm", "1"]) == 0
    fig = robot.RobotFigures(**json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    assert fig.build_s is not None and fig.build_s > 0 and fig.steps == 500 and fig.note == ""
    assert fig.native_ms > 0 and fig.runner_ms > 0 and fig.traced_ms > 0 and fig.native_loop
    # the hand-written loop replays the runner's servo targets on the adapter's own world: the same physics,
    # to rounding of 500 steps of the same operations (float64)
    assert fig.same_physics <= 1e-9
    assert (PyBulletBackend._step, PyBulletBackend.__init__) == (step, init)  # the wrappers are removed again
