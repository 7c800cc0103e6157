"""The golden file format and the comparison rules, on recordings built by hand (no engine)."""

from __future__ import annotations

import numpy as np
import pytest

from runner.ci.golden import (
    BaselineError,
    Recording,
    Tol,
    Tolerances,
    VerdictLine,
    dumps,
    quantize,
    sample_every,
    sample_steps,
)
from runner.ci.golden_compare import compare
from runner.ci.golden_read import loads
from runner.ci.regression import parse_tolerance_options
from runner.errors import UsageError


def recording(steps: int = 10, every: int = 2, engine: str = "1.0") -> Recording:
    """A falling box (semi-implicit Euler, dt 0.1) beside a static floor, one joint, two state variables."""
    dt = 0.1
    header = {
        "format": "1", "scenario": "drop", "variant": "base", "backend": "fake", "engine": engine, "tool": "0.1.0",
        "scenario_file": "drop.yaml", "scenario_sha256": "ab" * 32, "dt": "0.1", "steps": str(steps),
        "end_time": str(steps * dt), "status": "passed", "every": str(every),
    }  # fmt: skip
    rec = Recording(header=header, tolerances={"default": Tol(1e-6, 1e-6)})
    rec.steps = sample_steps(steps, every)
    n = np.array(rec.steps, float)
    box = np.zeros((len(n), 13))
    box[:, 2] = [quantize(2 - 9.81 * dt * dt * k * (k + 1) / 2) for k in n]
    box[:, 3] = 1.0
    box[:, 9] = [quantize(-9.81 * dt * k) for k in n]
    floor = np.zeros((len(n), 13))
    floor[:, 3] = 1.0
    rec.bodies = {"box": box, "floor": floor}
    rec.joints = {"slider": np.column_stack([0.01 * n, np.full(len(n), 0.1), np.full(len(n), np.nan)])}
    rec.state = {"door_open": [bool(k >= 4) for k in n], "label": ['say "hi" there' for _ in n]}
    rec.events = [(0.0, "start", "start"), (0.4, "space", "input")]
    rec.sounds = [(0.4, "thud", "start")]
    rec.verdicts = [VerdictLine("box falls far enough", True, 1.0, "0.46045", "0.46 ± 0.01")]
    return rec


def test_round_trip_is_exact_and_leaves_out_repeated_lines() -> None:
    rec = recording()
    text = dumps(rec)
    again = loads(text)
    assert dumps(again) == text
    np.testing.assert_array_equal(again.bodies["box"], rec.bodies["box"])
    np.testing.assert_array_equal(again.joints["slider"], rec.joints["slider"])  # NaN == NaN here
    assert again.state == rec.state and again.events == rec.events and again.sounds == rec.sounds
    assert again.verdicts == rec.verdicts
    lines = text.splitlines()
    assert sum(line.startswith("body ") and " floor " in line for line in lines) == 1  # the floor never moves
    assert sum(line.startswith("var ") and " door_open " in line for line in lines) == 2  # false, then true at 0.4
    assert 'verdict pass 1 "box falls far enough" 0.46045 "0.46 ± 0.01"' in lines
    assert rec.steps == [0, 2, 4, 6, 8, 10]


def test_sampling_grid_keeps_the_last_step() -> None:
    assert sample_steps(7, 3) == [0, 3, 6, 7]
    assert sample_every(0.04, None) == 2  # 0.1 s -> 2.5 steps -> 2
    assert sample_every(0.01, None) == 10 and sample_every(0.04, 0) == 1


def test_malformed_lines_name_file_and_line() -> None:
    text = dumps(recording()).replace("angvel 0 0 0", "angvel 0 0", 1)
    with pytest.raises(BaselineError, match=r"x\.golden:\d+: cannot read this line"):
        loads(text, "x.golden")
    with pytest.raises(BaselineError, match=r"y\.golden:2:1: unknown line kind `hello`"):
        loads("# a comment\nhello world\n", "y.golden")
    with pytest.raises(BaselineError, match=r"not a baseline file \(no format, scenario, variant, backend, every"):
        loads("dt 0.1\n", "z.golden")


def test_tolerance_layers_command_line_then_file_then_built_in() -> None:
    file = {"pos": Tol(1e-3, None), "box.pos": Tol(None, 0.5)}
    assert Tolerances({}, file).lookup("box", "pos") == (1e-3, 0.5)  # name.field and field of one layer combine
    assert Tolerances({}, file).lookup("door", "pos") == (1e-3, 1e-6)  # rtol from the built-in default
    assert Tolerances({"default": Tol(0.1, None)}, file).lookup("box", "pos") == (0.1, 0.5)
    assert Tolerances({}, {}).lookup("box", "event") == (1e-6, 0.0)
    parsed = parse_tolerance_options(["1e-3", "box.pos=0.5"], ["vel=0.01"])
    assert parsed == {"default": Tol(1e-3, None), "box.pos": Tol(0.5, None), "vel": Tol(None, 0.01)}
    with pytest.raises(UsageError):
        parse_tolerance_options(["pos=fast"], [])
    with pytest.raises(UsageError):
        parse_tolerance_options(["-1"], [])


def test_identical_recordings_match_and_nothing_moved() -> None:
    result = compare(recording(), loads(dumps(recording())), Tolerances({}, recording().tolerances))
    assert result.ok and not result.changes and result.version_warning() is None


def test_first_divergence_is_the_earliest_sample_beyond_tolerance() -> None:
    got = recording()
    got.bodies["box"][3:, 2] += 1e-3  # from the sample at step 6 (t = 0.6) on
    got.bodies["box"][5, 9] += 1e-9  # below the file's resolution: not even "moved"
    result = compare(recording(), got, Tolerances({}, got.tolerances))
    first = result.first
    assert first is not None
    assert (first.time, first.kind, first.name, first.field) == (pytest.approx(0.6), "body", "box", "pos.z")
    assert first.expected == f"{quantize(2 - 9.81 * 0.01 * 21):.9g}"
    assert [c.signal for c in result.changes] == ["box.pos.z"]
    assert compare(recording(), got, Tolerances({"pos": Tol(2e-3, 0)}, {})).ok  # a looser command line


def test_quaternion_sign_is_not_a_divergence() -> None:
    got = recording()
    got.bodies["box"][:, 3:7] *= -1
    assert compare(recording(), got, Tolerances({}, {})).ok


def test_event_sequences_names_order_and_times() -> None:
    tol = Tolerances({}, {})
    late = recording()
    late.events[1] = (0.5, "space", "input")
    d = compare(recording(), late, tol).first
    assert d is not None and (d.kind, d.name, d.field, d.time) == ("event", "space", "time", 0.4)
    assert compare(recording(), late, Tolerances({"event": Tol(0.2, 0)}, {})).ok
    renamed = recording()
    renamed.events[1] = (0.4, "mouse1", "input")
    d = compare(recording(), renamed, tol).first
    assert d is not None and (d.field, d.expected, d.got) == (
        "order",
        "space (input) at 0.4 s",
        "mouse1 (input) at 0.4 s",
    )
    missing = recording()
    missing.sounds = []
    d = compare(recording(), missing, tol).first
    assert d is not None and (d.kind, d.field, d.time) == ("sound", "missing", 0.4)


def test_verdict_flip_state_change_and_a_shorter_run() -> None:
    tol = Tolerances({}, {})
    flipped = recording()
    flipped.verdicts = [VerdictLine("box falls far enough", False, 1.0, "0.2", "0.46 ± 0.01")]
    kinds = [(d.kind, d.field) for d in compare(recording(), flipped, tol).divergences]
    assert kinds == [("verdict", "result")]
    other = recording()
    other.state["door_open"] = [False] * len(other.steps)
    d = compare(recording(), other, tol).first
    assert d is not None and (d.kind, d.name, d.time, d.expected, d.got) == ("var", "door_open", 0.4, "true", "false")
    short = recording(steps=7)
    d = compare(recording(), short, tol).first
    assert d is not None and (d.kind, d.name) == ("run", "end") and d.time == pytest.approx(0.7)


def test_engine_upgrade_warning_names_the_signals_that_moved() -> None:
    got = recording(engine="2.0")
    assert compare(recording(), got, Tolerances({}, {})).version_warning() == (
        "fake 2.0 is installed but the baseline was recorded with 1.0; no signal moved"
    )
    got.joints["slider"][2:, 0] += 3e-7  # inside the tolerance, but moved
    result = compare(recording(), got, Tolerances({}, {}))
    assert result.ok
    warning = result.version_warning()
    assert warning is not None and "signals that moved: slider.position (max 3e-07 at 0.4 s)" in warning
