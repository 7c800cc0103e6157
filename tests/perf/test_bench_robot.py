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
@pytest.mark.parametrize("name", ["kuka arm", "quadruped"])
def test_the_measuring_path(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    from backends.pybullet import PyBulletBackend

    step, init = PyBulletBackend._step, PyBulletBackend.__init__
    assert robot._child(["pybullet", name, "1"]) == 0
    fig = robot.RobotFigures(**json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    assert fig.build_s is not None and fig.build_s > 0 and fig.steps == 500 and fig.note == ""
    assert fig.native_ms > 0 and fig.runner_ms > 0 and fig.traced_ms > 0 and fig.native_loop
    # the hand-written loop replays the runner's servo targets on the adapter's own world with the runner's
    # servo law (the joints' velocity and effort limits; readings from the model's zero, which the quadruped's
    # knees, starting at their stops, are not at): the same float64 operations in the same order, so the same
    # joint positions to the bit after 500 steps
    assert fig.same_physics == 0.0
    assert (PyBulletBackend._step, PyBulletBackend.__init__) == (step, init)  # the wrappers are removed again
