"""The editor schema (runner/schema/scenario.schema.json), checked by tools we did not write.

`jsonschema` (Draft 2020-12) validates every scenario of `scenarios/` as the loader reads it; the real
`yaml-language-server` (npm, what VS Code's YAML extension and other editors run) opens every file over LSP
and must publish 0 diagnostics, and must point at a misspelt key. The server is installed by
`make editor-tools` into a cache folder outside the repository; without it the LSP tests skip, unless
`SCENARIO_REQUIRE_EDITOR=1` (set by `.ci/run`) turns the skip into a failure.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator

from runner.language.yaml_source import load_yaml
from tests.language.lsp import LanguageServer, server_command
from tests.paths import ROOT

SCHEMA_PATH = ROOT / "runner" / "schema" / "scenario.schema.json"
ALL_SCENARIOS = sorted((ROOT / "scenarios").rglob("*.yaml"))


def _refuse(constant: str) -> None:
    raise ValueError(f"not strict JSON: {constant}")


def schema() -> dict:
    return json.loads(SCHEMA_PATH.read_text(), parse_constant=_refuse)


def test_the_schema_is_strict_json() -> None:
    document = schema()  # Infinity, -Infinity or NaN would raise
    Draft202012Validator.check_schema(document)
    mu = document["$defs"]["Surface"]["properties"]["mu"]
    assert mu["default"] == "inf" and {"const": "inf"} in mu["anyOf"]


@pytest.mark.parametrize("path", ALL_SCENARIOS, ids=[str(p.relative_to(ROOT)) for p in ALL_SCENARIOS])
def test_every_scenario_is_valid_against_the_schema(path: Path) -> None:
    data, _ = load_yaml(path.read_text(), str(path))
    errors = Draft202012Validator(schema()).iter_errors(data)
    assert [f"{'.'.join(map(str, e.absolute_path))}: {e.message}" for e in errors] == []


PARAMS_EVERYWHERE = """\
schema_version: 1
scenario: p
params: {T: 2, m: kinematic, on: true, h: 0.5}
world: {dt: 0.01, duration: "${T}"}
surface: {mu: inf, bounce: "${h}"}
bodies:
  b: {box: [1, "${h}", 1], mass: 1, motion: "${m}", pos: [0, 0, "-${h}"]}
  c: {sphere: 0.1, density: 10, pos: [0, 0, 1]}
triggers:
  low: {when: c.pos.z < 0.5, once: "${on}"}
inputs: [{at: 0.99*param.T/2, event: go}]
on:
  go: [{log: go}]
  low: {do: [{log: low}], min_interval: dt*10}
assertions:
  - {name: fall, becomes: c.pos.z < 0.5, near: sqrt(2*0.5/g), tol: dt}
  - {name: top, max: c.pos.z, during: [0, param.T/2], time: 0, time_tol: dt}
"""


def test_params_and_time_expressions_are_valid_where_the_loader_takes_them(tmp_path: Path) -> None:
    from runner.language.load import load_scenario

    path = tmp_path / "p.yaml"
    path.write_text(PARAMS_EVERYWHERE)
    load_scenario(path)  # the loader accepts it...
    data, _ = load_yaml(PARAMS_EVERYWHERE, "p.yaml")
    assert list(Draft202012Validator(schema()).iter_errors(data)) == []  # ...and so does the schema


def test_a_misspelt_key_is_diagnosed_by_the_schema() -> None:
    text = (ROOT / "scenarios" / "factory_physics.yaml").read_text().replace("density: 500", "desnity: 500", 1)
    data, _ = load_yaml(text, "bad.yaml")
    messages = [e.message for e in Draft202012Validator(schema()).iter_errors(data)]
    assert any("'desnity' was unexpected" in m for m in messages), messages


# ---- the real editor server --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def server() -> Iterator[LanguageServer]:
    command = server_command()
    if command is None:
        if os.environ.get("SCENARIO_REQUIRE_EDITOR") == "1":
            pytest.fail("yaml-language-server is not installed (run `make editor-tools`) and CI requires it")
        pytest.skip("yaml-language-server not installed (run `make editor-tools`; needs node and npm)")
    ls = LanguageServer(command, ROOT)
    yield ls
    ls.close()


def _show(diagnostics: list[dict]) -> list[str]:
    return [f"{d['range']['start']['line'] + 1}: {d['message']}" for d in diagnostics]


def test_the_editor_server_finds_nothing_wrong_in_any_scenario(server: LanguageServer) -> None:
    found = {}
    for path in ALL_SCENARIOS:
        diagnostics = server.diagnostics(server.open(path))
        if diagnostics:
            found[str(path.relative_to(ROOT))] = _show(diagnostics)
    assert found == {}
    assert len(ALL_SCENARIOS) >= 17


def test_the_editor_server_points_at_a_misspelt_key(server: LanguageServer, tmp_path: Path) -> None:
    text = (ROOT / "scenarios" / "factory_physics.yaml").read_text()
    text = text.replace("$schema=../runner/schema", f"$schema={SCHEMA_PATH.parent.as_posix()}", 1)
    text = text.replace("density: 500", "desnity: 500", 1)
    path = tmp_path / "misspelt.yaml"
    path.write_text(text)
    line = next(i for i, row in enumerate(text.splitlines()) if "desnity" in row)
    diagnostics = server.diagnostics(server.open(path))
    assert [d for d in diagnostics if d["range"]["start"]["line"] == line and "desnity" in d["message"]], _show(
        diagnostics
    )


def test_the_editor_server_accepts_params_and_time_expressions(server: LanguageServer, tmp_path: Path) -> None:
    path = tmp_path / "params.yaml"
    path.write_text(f"# yaml-language-server: $schema={SCHEMA_PATH.as_posix()}\n" + PARAMS_EVERYWHERE)
    assert _show(server.diagnostics(server.open(path))) == []
