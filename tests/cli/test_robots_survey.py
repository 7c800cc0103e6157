"""`scenario robots survey` end to end on two real models (pybullet_data): one that runs, one refused before
it runs with the feature named; the table, its totals and the `--target` exit code."""

from __future__ import annotations

from pathlib import Path

import pytest

from runner.cli.main import main
from runner.errors import ExitCode

MODELS = ["@pybullet_data/cube_small.urdf", "@pybullet_data/torus_deform.urdf"]


def test_the_table_and_the_target(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "survey.md"
    code = main(["robots", "survey", *MODELS, "-b", "pybullet", "--duration", "0.05", "--out", str(out)])
    table = out.read_text()
    assert code == ExitCode.OK
    assert "| `@pybullet_data/cube_small.urdf` | ran |" in table
    assert "| `@pybullet_data/torus_deform.urdf` | refused: torus\\_deform.urdf\\:3\\: a deformable body" in table
    assert "| pybullet | 2 | 1 | 1 | 0 | 0 | 0 | 50 % |" in table  # models, ran, refused, crashed, ...
    capsys.readouterr()
    # 1 of 2 ran: 50 % meets a target of 50 and misses one of 51
    assert main(["robots", "survey", *MODELS, "-b", "pybullet", "--duration", "0.05", "--target", "50"]) == 0
    assert main(["robots", "survey", *MODELS, "-b", "pybullet", "--duration", "0.05", "--target", "51"]) == 1


def test_a_missing_folder_is_bad_input(tmp_path: Path) -> None:
    assert main(["robots", "survey", str(tmp_path / "nowhere"), "-b", "pybullet"]) == ExitCode.BAD_INPUT
