"""`scenario baseline --backend all` and `scenario check --backend all` (what CI runs over scenarios/*.yaml on
every installed engine, .ci/run): an engine that refuses a case up front sits it out, named with the missing
capability, as in `scenario compare`; a named engine that refuses it is an error (exit 2), as in `scenario run`;
and a refused case that has a golden file is a regression, so it is run and its refusal is the error."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from backends.registry import get_backend, installed_backends
from backends.types import Capability

from .conftest import cli

BOUNCY = """\
schema_version: 1
scenario: bouncy
world: {dt: 0.04, duration: 0.2}
surface: {bounce: 0.5, mu: 1.0}
bodies:
  ground: {plane: {}, motion: static}
  ball: {sphere: 0.1, density: 500, pos: [0, 0, 0.2]}
"""


def _engines() -> tuple[list[str], list[str]]:
    """(installed engines that run a bounce > 0, those that refuse it up front)."""
    engines = installed_backends()
    refusing = [e for e in engines if Capability.CONTACT_BOUNCE not in get_backend(e).capabilities]
    return [e for e in engines if e not in refusing], refusing


def test_every_engine_records_and_checks_what_it_runs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    running, refusing = _engines()
    if not refusing or not running:
        pytest.skip("needs one installed engine with contact:bounce and one without (drake has none)")
    scenario = tmp_path / "bouncy.yaml"
    scenario.write_text(BOUNCY)
    goldens = tmp_path / "b"
    code, text = cli(capsys, "baseline", scenario, "--backend", "all", "--baseline", goldens)
    assert code == 0, text
    assert sorted(p.name for p in goldens.iterdir()) == sorted(f"bouncy__base__{e}.golden" for e in running)
    for engine in refusing:
        assert f"not recorded: bouncy · base on {engine}, which refuses it up front (contact:bounce;" in text
    code, text = cli(capsys, "check", scenario, "--backend", "all", "--baseline", goldens, "--out", tmp_path / "t")
    assert code == 0, text
    assert f"{len(running)}/{len(running)} cases match their baselines and pass" in text
    for engine in refusing:
        assert f"not checked: bouncy · base on {engine}, which refuses it up front (contact:bounce;" in text
    named = refusing[0]
    code, text = cli(capsys, "check", scenario, "--backend", named, "--baseline", goldens, "--out", tmp_path / "t")
    assert code == 2 and "contact:bounce" in text, text
    # a golden file for the refusing engine: the case was recorded on it once, so its refusal now is an error
    shutil.copy(goldens / f"bouncy__base__{running[0]}.golden", goldens / f"bouncy__base__{named}.golden")
    code, text = cli(capsys, "check", scenario, "--backend", "all", "--baseline", goldens, "--out", tmp_path / "t")
    assert code == 2 and f"bouncy · base · {named}" in text, text
