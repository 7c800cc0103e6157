"""Recording options: every k-th step (``record_every``) and the trace written by a second process.

Short runs on PyBullet of the lab's scenes (events, sounds, collision solids); about 5 s.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from reports.trace_reader import read_trace
from runner.errors import TraceError
from runner.language.load import load_scenario
from runner.sim.run import run_loaded, trace_path
from runner.trace.process import BATCH_STEPS, BackgroundTraceWriter
from runner.trace.writer import TraceMeta
from tests.trace.test_trace import write_trace

ROOT = Path(__file__).resolve().parents[2]
PILE = ROOT / "scenarios" / "box_pile.yaml"
INTERVALS = ROOT / "scenarios" / "factory_intervals.yaml"


def test_record_every_keeps_every_kth_step_the_last_and_all_verdicts(tmp_path: Path) -> None:
    loaded = load_scenario(PILE, None, (("world.duration", 1.0),))
    full = run_loaded(loaded, "pybullet", tmp_path / "full")
    sparse = run_loaded(loaded, "pybullet", tmp_path / "sparse", record_every=7)
    assert [v.as_dict() for v in sparse.verdicts] == [v.as_dict() for v in full.verdicts]  # checked every step
    a, b = read_trace(full.trace), read_trace(sparse.trace)
    assert len(a.times) == 101
    assert list(b.times) == pytest.approx([k * 0.01 for k in range(0, 100, 7)] + [1.0])  # 0, 7, ..., 98, last
    assert b.scenario["record_every"] == "7"
    crate = "crate_4"
    assert b.bodies[crate].pos[-1] == pytest.approx(a.bodies[crate].pos[-1], abs=0)  # the same last state
    assert b.bodies[crate].pos[1] == pytest.approx(a.bodies[crate].pos[7], abs=0)


def test_trace_process_writes_the_same_bytes(tmp_path: Path) -> None:
    for variant in ("door-opened-first", "space-twice"):  # intervals, sounds, events, solids
        loaded = load_scenario(INTERVALS, variant)
        inline = run_loaded(loaded, "pybullet", tmp_path / "inline")
        process = run_loaded(loaded, "pybullet", tmp_path / "process", trace_process=True)
        assert inline.status == process.status == "passed"
        assert Path(process.trace).read_bytes() == Path(inline.trace).read_bytes()


def test_trace_process_sends_every_kind_of_call_in_batches_and_writes_the_same_bytes(tmp_path: Path) -> None:
    """53 steps = 3 full batches and a part; a NaN contact force, events, sounds, logs, a rescaled
    scene and state variables between steps, in the in-process writer's order."""
    steps = 3 * BATCH_STEPS + 5
    write_trace(tmp_path / "inline.mcap", steps=steps)
    write_trace(tmp_path / "process.mcap", steps=steps, writer=BackgroundTraceWriter)
    assert (tmp_path / "process.mcap").read_bytes() == (tmp_path / "inline.mcap").read_bytes()
    assert len(read_trace(tmp_path / "process.mcap").times) == steps


def test_trace_process_refuses_an_existing_trace_and_finishes_interrupted_runs(tmp_path: Path) -> None:
    loaded = load_scenario(PILE, None, (("world.duration", 0.1),))
    run_loaded(loaded, "pybullet", tmp_path)
    meta = TraceMeta("s", "v", "pybullet", "1", {}, 0.01, 1, 1.0, "t", "sha", "p.yaml", 1, (), (), [])
    with pytest.raises(TraceError, match="already exists"):  # the writer process refuses it, as the in-process one
        BackgroundTraceWriter(trace_path(tmp_path, loaded, "pybullet"), meta, force=False)
    path = tmp_path / "interrupted.mcap"
    with pytest.raises(KeyboardInterrupt), BackgroundTraceWriter(path, meta) as writer:
        writer.log(0.5, "info", "before the interruption")
        raise KeyboardInterrupt
    trace = read_trace(path)
    assert trace.status == "interrupted"
    assert [log.message for log in trace.logs] == ["before the interruption"]
    assert trace_path(tmp_path, loaded, "pybullet").is_file()
