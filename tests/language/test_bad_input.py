"""Broken scenario files -> a located error (file:line:column), the field, what was expected and found."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario

BASE = """\
schema_version: 1
scenario: t
world: {dt: 0.04, duration: 1}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
"""

# (name, yaml appended to or replacing BASE, expected line:col, regex the message must match)
CASES = [
    (
        "misspelt key",
        BASE.replace("density", "desnity"),
        "5:31",
        r"bodies\.box\.desnity: unknown key `desnity`; did you mean `density`\?",
    ),
    ("misspelt top key", BASE + "asertions: []\n", "6:1", r"unknown key `asertions`; did you mean `assertions`\?"),
    ("negative dt", BASE.replace("dt: 0.04", "dt: -0.04"), "3:13", r"world\.dt: .*greater than 0.*found -0\.04"),
    ("zero size", BASE.replace("[0.3, 0.3, 0.3]", "[0.3, 0, 0.3]"), "5:8", r"expected box sizes > 0"),
    ("no mass", BASE.replace(", density: 500", ""), "5:8", r"needs mass or density"),
    (
        "two shapes",
        BASE.replace("box: [0.3, 0.3, 0.3]", "box: [0.3, 0.3, 0.3], sphere: 1"),
        "5:8",
        r"exactly one shape .* found box, sphere",
    ),
    (
        "missing world",
        BASE.replace("world: {dt: 0.04, duration: 1}\n", ""),
        "1:1",
        r"world: missing required field `world`",
    ),
    ("wrong type", BASE.replace("duration: 1", "duration: soon"), "3:29", r"world\.duration: .*found 'soon'"),
    (
        "unknown joint body",
        BASE + "joints:\n  j: {type: slider, bodies: [bx, environment]}\n",
        "7:30",
        r"joints\.j\.bodies\[0\]: unknown body `bx`; did you mean `box`\?",
    ),
    (
        "unknown interval",
        BASE + "on:\n  space: [{start: opne}]\nintervals:\n  open: {lerp: {body: box, pos: [0,0,0], duration: 1}}\n",
        "7:19",
        r"unknown interval `opne`; did you mean `open`\?",
    ),
    (
        "lerp of a dynamic body",
        BASE + "intervals:\n  open: {lerp: {body: box, pos: [0,0,0], duration: 1}}\n",
        "7:23",
        r"intervals\.open\.lerp\.body: intervals move kinematic bodies; `box` is dynamic",
    ),
    (
        "unknown sound",
        BASE + "on:\n  space: [{play_sound: bang}]\n",
        "7:24",
        r"on\.space\[0\]\.play_sound: unknown sound `bang`",
    ),
    (
        "missing sound file",
        BASE + "sounds:\n  bang: nowhere.wav\n",
        "7:9",
        r"expected a WAV file at 'nowhere\.wav': file not found",
    ),
    (
        "sound outside the folder",
        BASE + "sounds:\n  bang: ../../etc/passwd\n",
        "7:9",
        r"must be inside the scenario's folder",
    ),
    ("not a wav", BASE + "sounds:\n  bang: t.yaml\n", "7:9", r"not a WAV file"),
    (
        "unknown event in an assertion",
        BASE + "assertions:\n  - {name: a, event: box-into-dor, count: 1}\ninputs: [{at: 0.1, event: box-into-door}]\n",
        "7:22",
        r"assertions\[0\]\.event: unknown event \(it can never happen\) `box-into-dor`; did you mean `box-into-door`\?",
    ),
    ("duplicate key", BASE + "bodies:\n  b: {sphere: 1, density: 1}\n", "6:1", r"duplicate key `bodies`"),
    (
        "non-planar polygon",
        BASE + "collisions:\n  nodes:\n    n: {body: box, polygon: [[0,0,0],[1,0,0],[1,1,0.5],[0,1,0]]}\n",
        "8:29",
        r"collisions\.nodes\.n\.polygon: the polygon is not planar",
    ),
    (
        "non-convex polygon",
        BASE + "collisions:\n  nodes:\n    n: {body: box, polygon: [[0,0,0],[2,0,0],[1,0.2,0],[2,2,0],[0,2,0]]}\n",
        "8:29",
        r"the polygon is not convex",
    ),
    (
        "expression outside the grammar",
        BASE + "assertions:\n  - {name: a, always: __import__('os')}\n",
        "7:23",
        r"unknown function `__import__`",
    ),
    (
        "unknown name in an expression",
        BASE + "assertions:\n  - {name: a, always: box.pos.q > 0}\n",
        "7:23",
        r"unknown name `box\.pos\.q` in expression; did you mean `box\.pos\.[xyz]`\?",
    ),
    (
        "bad action",
        BASE + "on:\n  space: [{strat: x}]\n",
        "7:11",
        r"expected an action .* found keys strat; did you mean `start`\?",
    ),
    (
        "unknown parameter",
        BASE.replace("density: 500", "density: '${rho}'"),
        "5:40",
        r"bodies\.box\.density: unknown parameter `rho`",
    ),
    ("bad yaml", BASE + "on: [\n", "7:1", r"invalid YAML"),
    ("python tag", BASE + "x: !!python/object/apply:os.system [ls]\n", "6:4", r"x: unsupported YAML tag"),
    (
        "unknown variant key",
        BASE + "variants:\n  v: {inputs: [], expect: []}\n",
        "7:19",
        r"variants\.v\.expect: unknown key `expect`; expected one of: assertions, description, inputs, set",
    ),
    ("nan", BASE.replace("pos: [0, 0, 1]", "pos: [0, 0, .nan]"), "5:50", r"bodies\.box\.pos: expected finite numbers"),
]


@pytest.mark.parametrize("name,text,where,pattern", CASES, ids=[c[0] for c in CASES])
def test_bad_file_is_located(tmp_path: Path, name: str, text: str, where: str, pattern: str) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    lines = str(info.value).splitlines()
    expected_prefix = f"{path}:{where}:"
    assert any(line.startswith(expected_prefix) and re.search(pattern, line) for line in lines), (
        f"wanted {expected_prefix} ... /{pattern}/, got:\n" + "\n".join(lines)
    )


def test_alias_bomb_is_refused(tmp_path: Path) -> None:
    lines = ["a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"]
    for i in range(1, 8):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]")
    path = tmp_path / "bomb.yaml"
    path.write_text(BASE + "\n".join(lines) + "\n")
    with pytest.raises(ScenarioValidationError, match="alias bomb"):
        load_scenario(path, None)


def test_several_problems_reported_together(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(textwrap.dedent(BASE).replace("density", "desnity").replace("duration: 1", "duration: -1"))
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    assert len(info.value.issues) == 2


def test_limits_on_bodies_and_steps(tmp_path: Path) -> None:
    path = tmp_path / "big.yaml"
    path.write_text(BASE.replace("duration: 1", "duration: 1.0e6")
                    + "  crate: {box: [1, 1, 1], density: 1, array: {count: [100, 60, 1]}}\n"
                    + "  brick: {box: [1, 1, 1], density: 1, array: {count: [100, 60, 1]}}\n")
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    text = str(info.value)
    assert "expected at most 10000 bodies (arrays expanded), found 12001" in text
    assert f"{path}:3:" in text and "expected at most 10000000 steps (duration / dt), found 25000000" in text
