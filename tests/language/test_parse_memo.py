"""A file is parsed once however many variants are loaded from it (issue 19: loading is the serial part of
`-j N`), and never served stale or shared: an edited file is parsed again, and what one case changes is not
seen by the next."""

from __future__ import annotations

from pathlib import Path

import pytest

from runner.language import load

SOURCE = """\
schema_version: 1
scenario: memo
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
bodies:
  ball: {sphere: 0.1, density: 1000, pos: [0, 0, 1]}
variants:
  low: {set: {bodies.ball.pos: [0, 0, 0.5]}}
  high: {set: {bodies.ball.pos: [0, 0, 2]}}
"""


def test_every_variant_of_a_file_comes_from_one_parse(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[str] = []
    real = load.load_yaml
    monkeypatch.setattr(load, "load_yaml", lambda text, file: calls.append(file) or real(text, file))
    source = tmp_path / "memo.yaml"
    source.write_text(SOURCE)
    cases = load.load_all(source, None, all_variants=True)
    assert [c.variant for c in cases] == ["low", "high"]
    assert [c.model.bodies["ball"].pos[2] for c in cases] == [0.5, 2.0]  # each variant applied to its own copy
    assert calls == [str(source)]


def test_an_edited_file_is_parsed_again(tmp_path: Path) -> None:
    source = tmp_path / "memo.yaml"
    source.write_text(SOURCE)
    assert load.load_scenario(source, "low").model.world.dt == 0.01
    source.write_text(SOURCE.replace("dt: 0.01", "dt: 0.02"))
    assert load.load_scenario(source, "low").model.world.dt == 0.02


def test_what_a_caller_changes_is_not_seen_by_the_next(tmp_path: Path) -> None:
    source = tmp_path / "memo.yaml"
    source.write_text(SOURCE)
    _, data, positions = load.read_source(source)
    data["bodies"]["ball"]["pos"][2] = 99
    positions.overridden[("world",)] = "--set world=..."
    positions.values[("bodies",)] = (99, 99)
    _, again, fresh = load.read_source(source)
    assert again["bodies"]["ball"]["pos"][2] == 1
    assert ("world",) not in fresh.overridden and fresh.values[("bodies",)] != (99, 99)
