"""The bench's robot section: refused engines are reported with their refusal, and the measuring path (build,
engine and runner milliseconds per step) works on an adapter that accepts robots (here the pure-Python one
made to accept them: a check of the machinery, not a figure)."""

from __future__ import annotations

import json

import pytest

from backends.fake import FakeBackend
from backends.types import Capability
from bench import robot


def test_a_refusing_engine_is_reported_with_its_refusal(capsys: pytest.CaptureFixture[str]) -> None:
    assert robot._child(["pybullet"]) == 0
    fig = robot.RobotFigures(**json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    if fig.build_s is None:  # until the pybullet adapter maps robots (issue 22, ENGINE phase)
        assert fig.note.startswith("refused up front: needs ") and "shape:compound" in fig.note
        assert f"| pybullet | | | | | {fig.note} |" in robot.render([fig])


@pytest.mark.slow
def test_the_measuring_path(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(FakeBackend, "capabilities", frozenset(Capability))
    assert robot._child(["fake"]) == 0
    fig = robot.RobotFigures(**json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    assert fig.build_s is not None and fig.build_s > 0 and fig.steps == 500
    assert fig.engine_ms > 0 and fig.runner_ms > 0
    assert FakeBackend._step.__name__ == "_step"  # the wrappers are removed again
