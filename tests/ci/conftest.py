"""Shared pieces of the regression tests: paths, the CLI in-process, goldens recorded once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from runner.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"
FACTORY = SCENARIOS / "factory_physics.yaml"
SCHEMA = Path(__file__).with_name("junit.xsd")


def cli(capsys: pytest.CaptureFixture[str], *args: str | Path) -> tuple[int, str]:
    """Run `scenario ARGS` in this process; (exit code, stdout + stderr)."""
    code = main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.out + captured.err


@pytest.fixture(scope="session")
def factory_goldens(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """factory_physics.yaml, every variant, recorded on PyBullet at every step (about 1 s)."""
    from runner.ci.regression import record_cases
    from runner.language.load import load_all

    directory = tmp_path_factory.mktemp("goldens")
    recorded = record_cases([(case, "pybullet") for case in load_all(FACTORY, None, True, ())], directory, period=0.0)
    assert all(rec is not None for _, _, rec in recorded), [res.headline for res, _, _ in recorded]
    return directory
