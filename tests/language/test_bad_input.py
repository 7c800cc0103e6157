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

def exact(message: str) -> str:
    """A pattern matching exactly this message (after the location)."""
    return "^" + re.escape(message) + "$"


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
    # keys inside a handler's actions and an `if` action's branches get their hints (the model is found through
    # the handler's list and the branch's list, whose item type `if` names before it is defined)
    (
        "misspelt key of an action in a handler",
        BASE + "inputs: [{at: 0.5, event: go}]\non:\n  go: [{force: {body: box, valu: [0, 0, 1]}}]\n",
        "8:28",
        exact("on.go[0].force.valu: unknown key `valu`; did you mean `value`?"),
    ),
    (
        "unknown key of an action in an if branch",
        BASE + "state: {x: 0}\ninputs: [{at: 0.5, event: go}]\non:\n"
        "  go: [{if: state.x > 1, then: [], else: [{set: {x: 2}, colr: 1}]}]\n",
        "9:57",
        exact("on.go[0].else[0].colr: unknown key `colr`; expected one of: set"),
    ),
    (
        "misspelt key of a handler",
        BASE + "inputs: [{at: 0.5, event: go}]\non:\n  go: {do: [{log: hi}], onse: true}\n",
        "8:25",
        r"on\.go\.onse: unknown key `onse`; did you mean `once`\?",
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
    # --- issue 18's silent mistakes and misleading messages, with their exact messages --------------------
    (
        "handler for an event that can never happen",
        BASE + "inputs: [{at: 0.5, event: space}]\non:\n  spaec: [{log: hi}]\n",
        "8:3",
        exact("on.spaec: a handler for an event that can never happen: unknown event `spaec`; did you mean `space`?"),
    ),
    (
        "assertion time after the end",
        BASE + "assertions:\n  - {name: a, at: 20, check: box.pos.z > 0}\n",
        "7:19",
        exact("assertions[0].at: a time at 20 s is after the end of the run (world.duration 1 s)"),
    ),
    (
        "input after the end",
        BASE + "inputs: [{at: 9, event: space}]\non: {space: [{log: hi}]}\n",
        "6:15",
        exact("inputs[0].at: an input at 9 s is after the end of the run (world.duration 1 s)"),
    ),
    (
        "window after the end",
        BASE + "assertions:\n  - {name: a, always: box.pos.z > 0, during: [0.5, 2]}\n",
        "7:52",
        exact("assertions[0].during[1]: a time at 2 s is after the end of the run (world.duration 1 s)"),
    ),
    (
        "window backwards",
        BASE + "assertions:\n  - {name: a, always: box.pos.z > 0, during: [0.8, 0.2]}\n",
        "7:46",
        exact("assertions[0].during: expected a window [start, end] with start <= end, found [0.8, 0.2]"),
    ),
    (
        "unknown backend option, as `run` refuses it",
        BASE + "backend_options: {pybullet: {solver_iteration: 10}}\n",
        "6:30",
        exact("backend_options.pybullet.solver_iteration: unknown option `solver_iteration` of backend `pybullet`; "
              "did you mean `solver_iterations`?"),
    ),
    (
        "unknown backend in backend_options",
        BASE + "backend_options: {pybulet: {}}\n",
        "6:19",
        exact("backend_options.pybulet: unknown backend `pybulet`; did you mean `pybullet`?"),
    ),
    (
        "an expression in a window is reported at the window",
        BASE + "assertions:\n  - {name: a, always: box.pos.z > 0, during: [0, box.pos.z]}\n",
        "7:50",
        exact("assertions[0].during[1]: cannot use `box.pos.z` in the time 'box.pos.z': a time is fixed when the "
              "scenario is loaded; it may read param.<name>, dt, duration, g, gravity.x|y|z, pi, e, inf"),
    ),
    (
        "two numbers for a position",
        BASE.replace("pos: [0, 0, 1]", "pos: [-0.8, -0.125]"),
        "5:50",
        exact("bodies.box.pos: expected a list of 3 numbers [x, y, z]; found 2 items"),
    ),
    (
        "two sizes for a box",
        BASE.replace("box: [0.3, 0.3, 0.3]", "box: [0.2, 0.2]"),
        "5:14",
        exact("bodies.box.box: expected a list of 3 sizes [x, y, z]; found 2 items"),
    ),
    (
        "four numbers for a position",
        BASE.replace("pos: [0, 0, 1]", "pos: [0, 0, 1, 2]"),
        "5:50",
        exact("bodies.box.pos: expected a list of 3 numbers [x, y, z]; found 4 items"),
    ),
    (
        "a function with too few arguments",
        BASE + "assertions:\n  - {name: a, at: end, check: clamp(1) > 0}\n",
        "7:31",
        exact("assertions[0].check: clamp() takes 3 arguments (x, lo, hi), found 1 at character 1 in expression "
              "'clamp(1) > 0'"),
    ),
    (
        "interval cycle through two intervals",
        BASE + "intervals:\n  ia: {parallel: [{interval: ib}]}\n  ib: {sequence: [{interval: ia}]}\n",
        "8:30",
        exact("intervals.ib.sequence[0].interval: intervals `ia` -> `ib` -> `ia` form a cycle; an interval cannot "
              "inline itself"),
    ),
    (
        "NUL in a sound path",
        BASE + 'sounds: {s: "sounds/thud.wav\\0"}\n',
        "6:13",
        exact("sounds.s: a NUL character in text (written as an escape); control characters are refused"),
    ),
    (
        "over-long variant name",
        BASE + "variants:\n  " + "v" * 300 + ": {}\n",
        "7:3",
        exact("variants." + "v" * 300 + ": expected at most 64 characters (the name is part of trace file names); "
              "found 300"),
    ),
    (
        "a time reading the state",
        BASE + "inputs: [{at: 0.5*box.pos.z, event: go}]\non: {go: [{log: x}]}\n",
        "6:15",
        exact("inputs[0].at: cannot use `box.pos.z` in the time '0.5*box.pos.z': a time is fixed when the scenario "
              "is loaded; it may read param.<name>, dt, duration, g, gravity.x|y|z, pi, e, inf"),
    ),
    (
        "a lerp start without its end (found by the structured fuzzer)",
        BASE.replace("density: 500, ", "motion: kinematic, ")
        + "intervals:\n  i: {lerp: {body: box, duration: 1, pos: [0, 0, 2], start_hpr: [0, 0, 0]}}\n",
        "7:13",
        exact("intervals.i.lerp: `start_hpr` is given without `hpr` (a start needs an end to lerp to)"),
    ),
    (
        "an integer beyond a float in the gravity (found by the loader fuzzing)",
        BASE.replace("world: {dt: 0.04, duration: 1}", "world: {dt: 0.04, duration: 1, gravity: [1" + "0" * 400
                     + ", 0, -9.81]}"),  # fmt: skip
        "3:42",
        r"^world\.gravity\[0\]: input should be a valid number; found 10000",
    ),
    (
        "a trigger named start",
        BASE + "triggers: {start: {when: box.pos.z < 0}}\n",
        "6:12",
        exact("triggers.start: `start` is the event sent before the first step; name the trigger otherwise"),
    ),
]


# (name, yaml, expected line:col, pattern) of cases loaded as their variant `v`
VARIANT_CASES = [
    (
        "a variant sets into a list",
        BASE.replace("world: {dt: 0.04, duration: 1}", "world: [1, 0, 0]")
        + "variants:\n  v: {set: {world.dt: 0.01}}\n",
        "7:13",
        exact("variants.v.set.world.dt: cannot set `world.dt`: `world` is a list, not a mapping"),
    ),
    (
        "a variant sets an undeclared parameter",
        BASE + "params: {count: 3}\nvariants:\n  v: {set: {params.cont: 4}}\n",
        "8:13",
        exact("variants.v.set.params.cont: unknown parameter `cont` (a dotted path replaces a value, it does not "
              "declare one); did you mean `count`?"),
    ),
]


@pytest.mark.parametrize("name,text,where,pattern", CASES, ids=[c[0] for c in CASES])
def test_bad_file_is_located(tmp_path: Path, name: str, text: str, where: str, pattern: str) -> None:
    check_located(tmp_path, text, where, pattern, None)


@pytest.mark.parametrize("name,text,where,pattern", VARIANT_CASES, ids=[c[0] for c in VARIANT_CASES])
def test_bad_variant_is_located(tmp_path: Path, name: str, text: str, where: str, pattern: str) -> None:
    check_located(tmp_path, text, where, pattern, "v")


def check_located(tmp_path: Path, text: str, where: str, pattern: str, variant: str | None) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, variant)
    lines = str(info.value).splitlines()
    expected_prefix = f"{path}:{where}:"
    assert any(line.startswith(expected_prefix) and re.search(pattern, line[len(expected_prefix):].strip())
               for line in lines), (
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


@pytest.mark.parametrize("handler", ["[{force: {body: box, valu: [0, 0, 1]}}]",
                                     "{do: [{force: {body: box, valu: 1}}]}"])  # fmt: skip
def test_a_handler_s_errors_are_its_own_form_s(tmp_path: Path, handler: str) -> None:
    """`on: {event: [actions] | {do: [actions], ...}}`: a mistake inside one form is reported there, without the
    other form's "should be a list / a dictionary" at the event (which said nothing about the mistake)."""
    path = tmp_path / "t.yaml"
    path.write_text(BASE + f"inputs: [{{at: 0.5, event: go}}]\non:\n  go: {handler}\n")
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(path, None)
    messages = [issue.message for issue in info.value.issues]
    assert any("unknown key `valu`; did you mean `value`?" in m for m in messages), messages
    assert not any("valid dictionary" in m or "valid list" in m for m in messages), messages
