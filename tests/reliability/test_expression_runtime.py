"""Expressions at run time: a wrong type stops the run as bad input, never with a traceback; nothing
unbounded is built; a failed operation (NaN) never makes an assertion pass.

Found by this suite: `box.pos.z + 'a'`, `max: crate.pos.z` (a group), `value: "'abc'"`, `min()` and a
`send` loop each raised a raw TypeError/ValueError/ExpressionError/ActionError (exit 1, traceback);
`'a' * 100000000000` raised MemoryError (and a smaller count would have allocated it); `check:
round(inf) > 0` and `always: sqrt(-1) > 0` passed, because the whole expression became NaN and
bool(NaN) is true.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from reports.trace_reader import read_trace
from runner.errors import ScenarioError
from runner.language.expressions import ExpressionError, compile_expression
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

BASE = """\
schema_version: 1
scenario: rt
world: {dt: 0.04, duration: 0.2}
state: {s: 0, mode: idle}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
  crate: {box: [0.3, 0.3, 0.3], density: 500, pos: [3, 0, 1], array: {count: 3}}
"""


def run(tmp_path: Path, extra: str, trace: bool = False):  # noqa: ANN201 - a RunResult
    path = tmp_path / "rt.yaml"
    path.write_text(BASE + extra)
    return run_loaded(load_scenario(path, None), "fake", tmp_path / "out" if trace else None)


@pytest.mark.parametrize(
    "extra,expression",
    [
        ("assertions:\n  - {name: a, always: \"box.pos.z + 'a' > 0\"}\n", "box.pos.z + 'a' > 0"),
        ("on:\n  start: [{if: \"box.pos.z < 'a'\", then: []}]\n", "box.pos.z < 'a'"),
        ('on:\n  start: [{calc: {s: "state.mode * 2"}}]\n', "state.mode * 2"),
        ("assertions:\n  - {name: a, max: crate.pos.z, during: [0, end], near: 1, tol: 1}\n", "crate.pos.z"),
        ("assertions:\n  - {name: a, at: end, value: \"'abc'\", near: 1, tol: 1}\n", "'abc'"),
        ("assertions:\n  - {name: a, at: end, value: box.pos.z, near: state.mode, tol: 1}\n", "state.mode"),
        ("assertions:\n  - {name: a, at: end, check: min() > 0}\n", "min() > 0"),
        ("assertions:\n  - {name: a, at: end, check: len(box.pos.z) > 0}\n", "len(box.pos.z) > 0"),
    ],
)
def test_a_type_error_stops_the_run_as_bad_input_naming_the_expression(
    tmp_path: Path, extra: str, expression: str
) -> None:
    with pytest.raises(ScenarioError) as info:
        run(tmp_path, extra)
    assert expression in str(info.value)


def test_an_event_loop_stops_the_run_as_bad_input(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="nested deeper than"):
        run(tmp_path, "on:\n  start: [{send: start}]\n")


class Values:
    def __init__(self) -> None:
        self.values = {"crate.pos.z": [1.0, 2.0, 3.0], "state.mode": "idle"}

    def value(self, name: str) -> object:
        return self.values[name]

    def call(self, func: str, args: list[object]) -> object:
        return True


@pytest.mark.parametrize(
    "text", ["'ab' * 3", "3 * 'ab'", "crate.pos.z * 2", "crate.pos.z + crate.pos.z", "'%s' % 1", "state.mode + 'x'"]
)
def test_text_and_lists_are_not_repeated_or_joined(text: str) -> None:
    """`'a' * 10**11` asked for 100 GB; text and lists take no part in arithmetic."""
    with pytest.raises(ExpressionError):
        compile_expression(text).evaluate(Values())


@pytest.mark.parametrize(
    "assertion",
    [
        "{name: a, at: end, check: round(inf) > 0}",
        "{name: a, always: sqrt(-1) > 0}",
        "{name: a, eventually: log(0) > 0}",
        "{name: a, at: end, check: floor(0*inf) == floor(0*inf)}",
    ],
)
def test_a_failed_operation_never_makes_an_assertion_pass(tmp_path: Path, assertion: str) -> None:
    result = run(tmp_path, f"assertions:\n  - {assertion}\n")
    assert [v.passed for v in result.verdicts] == [False]


def test_the_command_exits_2_and_the_trace_is_finished_with_the_error(tmp_path: Path) -> None:
    path = tmp_path / "rt.yaml"
    path.write_text(BASE + "assertions:\n  - {name: a, always: \"box.pos.z + 'a' > 0\"}\n")
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", str(path), "--backend", "fake", "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and "box.pos.z + 'a' > 0" in done.stderr
    trace = read_trace(tmp_path / "out" / "rt__base__fake.mcap")
    assert trace.status == "error" and "box.pos.z + 'a' > 0" in json.dumps(trace.summary)
    assert trace.times.tolist() == [0.0]  # stopped at the first check, after the first recorded state


BIG = "1" * 400  # an integer literal beyond the float range, in YAML
SQUARING = f"""\
schema_version: 1
scenario: sq
world: {{dt: 0.01, duration: 0.5}}
state: {{s: 3, b: {BIG}, t: 0}}
bodies:
  box: {{box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}}
inputs: [{{at: 0, event: sq, repeat: {{every: 0.01, count: 45}}}}]
on:
  sq: [{{calc: {{s: "state.s * state.s * floor(1e308)"}}}}, {{set: {{t: {BIG}}}}}]
assertions:
  - {{name: bounded, at: end, check: "state.s == inf and state.b > 1e300 and state.t > 1e300"}}
  - {{name: value, at: end, value: "floor(1e308)*floor(1e308)", min: 0}}
"""


@pytest.mark.parametrize("options", [[], ["--no-trace"], ["--trace-process"], ["-j", "2"]])
def test_integers_are_bounded_on_every_path(tmp_path: Path, options: list[str]) -> None:
    """Squaring an integer state 45 times would be 3**(2**45) (terabytes; the probe saw 5.7 GB with
    --no-trace, a run that never ended with --trace-process, and OverflowError, exit 70, serially): integers
    beyond 2**53 become floats, inf beyond their range, in calc, set, state, assertion values."""
    path = tmp_path / "sq.yaml"
    path.write_text(SQUARING)
    done = subprocess.run(
        [sys.executable, "-m", "runner", "run", str(path), "--backend", "fake", "--out", str(tmp_path / "out"),
         *options],
        capture_output=True,
        text=True,
        timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert "2/2 assertions" in done.stdout + done.stderr


def test_an_integer_overflow_in_a_time_is_a_located_error(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(BASE + 'assertions:\n  - {name: a, at: "floor(1e308)*floor(1e308)", check: box.pos.z > 0}\n')
    done = subprocess.run(
        [sys.executable, "-m", "runner", "validate", str(path)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 2, done.stderr
    assert f"{path}:9:19:" in done.stderr and "expected a finite time" in done.stderr and "inf" in done.stderr


def test_a_negative_base_to_a_fractional_power_is_nan_not_complex(tmp_path: Path) -> None:
    """`(z-1)**0.5` was a complex number, then a type error (exit 2); docs/language.md says NaN, and NaN
    is false."""
    result = run(tmp_path, 'assertions:\n  - {name: a, at: end, check: "(box.pos.z - 2)**0.5 > 0 or True"}\n'
                 '  - {name: b, at: end, check: "(box.pos.z - 2)**0.5 > 0"}\n')  # fmt: skip
    assert [v.passed for v in result.verdicts] == [True, False]
