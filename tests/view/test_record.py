"""``--record``: the played inputs written into the scenario file, by insertion only.

Every example scenario gets a variant: its old lines are all still there, in order and unchanged
(comments and layout too), every old variant loads to the same model, and the new inputs load on the
very steps they were played at. The times are the shortest decimals the loader maps back to those steps,
for every step of several time steps, including ones that are not exact in binary.
"""

from __future__ import annotations

import difflib
import shutil
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from runner.compile.program import build_program
from runner.errors import UsageError
from runner.language.load import load_scenario
from runner.sim.assertions import Verdict
from runner.view.record import Played, due_step, input_time, plan_record, write_record
from tests.paths import SCENARIOS
from tests.view.conftest import ROOT, copy_scenario

pytest.importorskip("ruamel.yaml", reason="library not installed: ruamel.yaml (the view extra)")

VERDICTS = [Verdict("kick", "value", True, "2.57", "2.57 ± 0.001"), Verdict("rest", "value", False, "0.5", "0.2")]


@given(st.sampled_from([0.04, 0.01, 1 / 60, 0.001, 0.1, 1 / 240, 0.03]), st.integers(0, 200_000))
def test_a_recorded_time_maps_back_to_its_step(dt: float, step: int) -> None:
    t = input_time(step, dt)
    assert due_step(t, dt) == step
    assert abs(t - step * dt) < 0.5e-9  # the step's time, as the trace has it (nanoseconds)
    assert len(repr(t)) <= len(repr(step * dt))


def test_short_times_for_the_labs_step() -> None:
    assert [input_time(k, 0.04) for k in (0, 1, 30, 38, 57, 175)] == [0.0, 0.04, 1.2, 1.52, 2.28, 7.0]


def _added(old: str, new: str) -> list[str]:
    ops = difflib.SequenceMatcher(a=old.splitlines(), b=new.splitlines(), autojunk=False).get_opcodes()
    assert all(tag in ("equal", "insert") for tag, *_ in ops), "an existing line changed"
    return [line for tag, _, _, j1, j2 in ops if tag == "insert" for line in new.splitlines()[j1:j2]]


@pytest.mark.parametrize("source", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_every_example_gets_its_variant_by_insertion_only(tmp_path: Path, source: Path) -> None:
    path = copy_scenario(source, tmp_path)
    old = path.read_text()
    names = load_scenario(path).model.variants
    loaded = load_scenario(path, next(iter(names)) if names else None)
    program = build_program(loaded)
    dt = program.world.dt
    played = [Played(3, "space"), Played(3, "shift-space"), Played(min(50, program.steps - 1), "mouse1")]
    plan = plan_record(loaded, "played-here")
    added = write_record(plan, loaded, played, dt, VERDICTS, "pybullet", "3.2.7")
    new = path.read_text()
    lines = _added(old, new)
    assert "\n".join(lines) + "\n" == (added if not plan.new_block else "variants:\n" + added)
    assert any("FAIL rest: measured 0.5, expected 0.2" in line for line in lines)
    recorded = build_program(load_scenario(path, "played-here"))
    before = [(i.step, i.event) for i in program.inputs]
    assert sorted([(i.step, i.event) for i in recorded.inputs]) == sorted(before + [(p.step, p.event) for p in played])
    assert recorded.world.duration == program.world.duration  # the played variant's `set` came along
    assert [a.name for a in recorded.loaded.model.assertions] == [a.name for a in loaded.model.assertions]


def test_comments_and_layout_stay(tmp_path: Path) -> None:
    path = copy_scenario(ROOT / "scenarios" / "factory_physics.yaml", tmp_path)
    old = path.read_text()
    loaded = load_scenario(path, "door-moves-away-box-falls")
    write_record(plan_record(loaded, "mine"), loaded, [Played(30, "space")], 0.04, VERDICTS, "ode", "0.16")
    new = path.read_text()
    assert new.startswith(old.rstrip("\n"))  # variants is the file's last block: everything before is untouched
    tail = new[len(old.rstrip("\n")) :]
    assert "\n  mine:\n" in tail and "{at: 1.2, event: space}" in tail and "{at: 1.52, event: space}" in tail
    assert "world.duration: 10" in tail


def test_a_variant_is_added_before_the_blocks_that_follow(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    shutil.copy(ROOT / "scenarios" / "factory_physics.yaml", path)
    text = path.read_text()
    head, _, variants = text.partition("\nvariants:\n")
    moved = head + "\nvariants:\n" + variants + "\n# the parameters\nparams:\n  unused: 1  # kept\n"
    path.write_text(moved)
    loaded = load_scenario(path, "door-stays-closed")
    write_record(plan_record(loaded, "mine"), loaded, [Played(30, "space")], 0.04, VERDICTS, "ode", "0.16")
    new = path.read_text()
    _added(moved, new)
    assert new.index("  mine:") < new.index("# the parameters") and new.endswith("params:\n  unused: 1  # kept\n")
    assert [(i.step, i.event) for i in build_program(load_scenario(path, "mine")).inputs] == [(30, "space")]


def test_a_file_without_variants_gets_a_variants_block(tmp_path: Path) -> None:
    path = copy_scenario(ROOT / "scenarios" / "box_pile.yaml", tmp_path)
    loaded = load_scenario(path)
    plan = plan_record(loaded, "mine")
    assert plan.new_block
    write_record(plan, loaded, [Played(2, "space")], build_program(loaded).world.dt, [], "ode", "0.16")
    assert "\nvariants:\n  # Recorded by `scenario view`" in path.read_text()
    assert load_scenario(path).model.model_dump(exclude={"variants"}) == loaded.model.model_dump(exclude={"variants"})


def test_what_cannot_be_recorded_is_refused_before_the_window_opens(tmp_path: Path) -> None:
    path = copy_scenario(ROOT / "scenarios" / "factory_physics.yaml", tmp_path)
    loaded = load_scenario(path, "door-stays-closed")
    with pytest.raises(UsageError, match=r"factory_physics.yaml:89:3: variant `door-opens-with-the-box-on-it` already"):
        plan_record(loaded, "door-opens-with-the-box-on-it")
    with pytest.raises(UsageError, match="base case"):
        plan_record(loaded, "base")
    flow = tmp_path / "flow.yaml"
    flow.write_text(path.read_text().split("\nvariants:\n")[0] + "\nvariants: {a: {inputs: []}}\n")
    with pytest.raises(UsageError, match="flow style"):
        plan_record(load_scenario(flow, "a"), "mine")


def test_a_file_changed_meanwhile_is_not_overwritten(tmp_path: Path) -> None:
    path = copy_scenario(ROOT / "scenarios" / "factory_physics.yaml", tmp_path)
    loaded = load_scenario(path, "door-stays-closed")
    plan = plan_record(loaded, "mine")
    path.write_text(path.read_text() + "# edited in an editor\n")
    edited = path.read_text()
    with pytest.raises(UsageError, match="changed while the window was open"):
        write_record(plan, loaded, [Played(30, "space")], 0.04, [], "ode", "0.16")
    assert path.read_text() == edited
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_a_command_line_set_is_recorded_with_the_played_inputs(tmp_path: Path) -> None:
    """`scenario view --set`: the recorded variant replays the run that was played, so the values set on the
    command line go into its `set:` (beside the played variant's own, which they beat, as in the run)."""
    path = copy_scenario(ROOT / "scenarios" / "factory_physics.yaml", tmp_path)
    overrides = (("world.duration", 12.0), ("world.dt", 0.02))
    loaded = load_scenario(path, "door-moves-away-box-falls", overrides)
    assert build_program(loaded).world.duration == 12.0  # beats the variant's own `world.duration: 10`
    write_record(plan_record(loaded, "mine"), loaded, [Played(30, "space")], 0.02, VERDICTS, "ode", "0.16")
    replay = build_program(load_scenario(path, "mine"))
    assert (replay.world.duration, replay.world.dt) == (12.0, 0.02)
    assert (30, "space") in [(i.step, i.event) for i in replay.inputs]
