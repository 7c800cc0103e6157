"""Batched sweeps (`scenario sweep --batch`, runner/exec/batched.py, runner/sim/lockstep.py) on the fake
backend's world batch: the same table and traces as separate runs, the fallback and its reason, variants that
end or fail dropping out while the others go on, and the progress of the batch's steps.

The scenario is a free fall, exact on the fake backend: after n steps z = z0 - g dt^2 n (n + 1)/2 (semi-implicit
Euler), to 1e-9 (float64 rounding of 50 steps is below 1e-13 m). About 10 s in all."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console

from backends.fake import FakeWorldBatch
from reports.trace_reader import read_trace
from runner.cli.main import main
from runner.cli.progress import BatchProgress
from runner.exec.batched import BatchedExecutor
from runner.exec.executors import Case, LocalExecutor
from runner.language.load import load_scenario
from runner.sim.lockstep import NotBatched, run_batch
from runner.sim.run import run_loaded

FALL = """\
schema_version: 1
scenario: batch-fall
params: {z0: 10.0, m: 1.0, gz: -9.81, stop: -1000000000.0, push: 0.0, count: 1}
world: {gravity: [0, 0, "${gz}"], dt: 0.01, duration: 0.5}
bodies:
  ball: {sphere: 0.1, mass: "${m}", pos: [0, 0, "${z0}"]}
  other: {sphere: 0.1, mass: 1, pos: [5, 0, 10], array: {count: "${count}", spacing: [1, 0, 0]}}
triggers:
  low: {when: ball.pos.z < param.stop}
on:
  start: [{force: {body: ball, value: [0, 0, "${push}"]}}]
  low: [{end: fell below the stop}]
assertions:
  - name: height-at-end
    at: end
    value: ball.pos.z
    near: param.z0 - g*dt*dt*round(time/dt)*(round(time/dt) + 1)/2
    tol: 1e-9
  - name: above-one-metre
    at: end
    value: ball.pos.z
    min: 1.0
"""


@pytest.fixture
def fall(tmp_path: Path) -> Path:
    path = tmp_path / "fall.yaml"
    path.write_text(FALL)
    return path


def _sweep(fall: Path, out: Path, *extra: str) -> int:
    return main(["sweep", str(fall), "--param", "z0=0.5,2,10", "--param", "m=0.1,1", "--param", "gz=-9.81,-1.62",
                 "-b", "fake", "--out", str(out), "-q", *extra])  # fmt: skip


def _files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*.mcap"))}


def test_a_batched_sweep_gives_the_table_and_traces_of_separate_runs(fall: Path, tmp_path: Path) -> None:
    assert _sweep(fall, tmp_path / "alone") == 1  # the low drops end below 1 m: failed, exit 1
    assert _sweep(fall, tmp_path / "batch", "--batch", "--traces") == 1
    alone, batch = tmp_path / "alone", tmp_path / "batch"
    assert (batch / "sweep.csv").read_text() == (alone / "sweep.csv").read_text()
    assert json.loads((batch / "sweep.json").read_text()) == json.loads((alone / "sweep.json").read_text())
    assert (batch / "sweep.svg").read_text() == (alone / "sweep.svg").read_text()
    traces = _files(alone)
    assert len(traces) == 12 and _files(batch) == traces  # byte-identical traces
    rows = list(csv.DictReader((alone / "sweep.csv").read_text().splitlines()))
    assert {r["height-at-end"] for r in rows} == {"pass"}  # the exact free fall in every world
    # z(0.5 s) = z0 - g*0.01^2*50*51/2 = z0 - 1.25 m (g 9.81) or 0.21 m (g 1.62): below 1 m from z0 = 0.5, and
    # from z0 = 2 at g 9.81 (rows: z0, then m, then gz)
    assert [r["above-one-metre"] for r in rows] == ["FAIL"] * 4 + ["FAIL", "pass"] * 2 + ["pass"] * 4


def test_without_traces_a_batch_writes_only_the_table(fall: Path, tmp_path: Path) -> None:
    assert _sweep(fall, tmp_path / "alone") == 1
    assert _sweep(fall, tmp_path / "batch", "--batch") == 1
    alone = list(csv.reader((tmp_path / "alone" / "sweep.csv").read_text().splitlines()))
    batch = list(csv.reader((tmp_path / "batch" / "sweep.csv").read_text().splitlines()))
    assert [r[:-1] for r in batch] == [r[:-1] for r in alone]  # all but the trace column
    assert {r[-1] for r in batch[1:]} == {""} and not (tmp_path / "batch" / "traces").exists()


def test_the_fallback_runs_separately_and_says_why(fall: Path, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    code = main(["sweep", str(fall), "--param", "count=1,2", "-b", "fake", "--batch", "--out", str(tmp_path / "a"),
                 "-q"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 0
    assert "--batch: variant 1 has 3 bodies, where variant 0 has 2; the 2 cases on fake run separately" in err
    rows = json.loads((tmp_path / "a" / "sweep.json").read_text())["rows"]
    assert [r["status"] for r in rows] == ["passed", "passed"] and not any(r["trace"] for r in rows)  # on request
    # a variant that adds a body is a batch of its own: base and two-others each batch their 2 cases
    variants = tmp_path / "variants.yaml"
    variants.write_text(FALL + "variants:\n  two-others:\n    set: {params.count: 2}\n")
    code = main(["sweep", str(variants), "--param", "z0=5,10", "-b", "fake", "--batch", "--all-variants",
                 "--out", str(tmp_path / "b"), "-q"])  # fmt: skip
    assert code == 0 and "--batch" not in capsys.readouterr().err
    cases = [Case(str(fall), None, "fake", (("params.z0", z),)) for z in (5.0, 10.0)]
    said: list[tuple[str, str]] = []
    results = BatchedExecutor(LocalExecutor(), on_fallback=lambda b, why: said.append((b, why))).run(
        [*cases, *(Case(c.path, None, "crash", c.overrides) for c in cases[:1])]
    )
    assert said == [("the case on crash", "backend crash does not batch worlds")]
    assert [r.status for r in results[:2]] == ["passed", "passed"]
    assert results[2].status == "crashed"  # run alone, the crash backend kills its worker as it always does


def test_an_ended_variant_drops_out_and_the_others_go_on(fall: Path, tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    seen: list[list[bool]] = []
    step_all = FakeWorldBatch.step_all

    def watched(self: FakeWorldBatch, active: list[bool]) -> dict[int, object]:
        seen.append(list(active))
        return step_all(self, active)  # type: ignore[return-value]

    monkeypatch.setattr(FakeWorldBatch, "step_all", watched)
    stops = (-1e9, 9.5, 9.0)  # z0 10: below 9.5 m after 32 steps (z = 10 - 9.81e-4*n(n+1)/2), 9 m after 45
    loads = [load_scenario(fall, None, (("params.stop", s),)) for s in stops]
    results = run_batch(loads, "fake", [None, None, None])
    alone = [run_loaded(loaded, "fake", None) for loaded in loads]
    assert [r.steps for r in results] == [r.steps for r in alone] == [50, 32, 45]
    assert [r.end_time for r in results] == [r.end_time for r in alone]
    assert [r.status for r in results] == ["passed"] * 3
    assert len(seen) == 50 and seen[31] == [True, True, True] and seen[32] == [True, False, True]
    assert seen[45] == [True, False, False] and seen[-1] == [True, False, False]


def test_a_world_the_runner_finds_blown_up_drops_out_alone(fall: Path) -> None:
    # 1e9 N on 0.1 kg for one 0.01 s step: 1e8 m/s, over the runner's blow-up limit (1e4 m/s) after step 1
    cases = [Case(str(fall), None, "fake", (("params.push", p), ("params.m", 0.1)), None) for p in (0.0, 1e9, 0.0)]
    batched = BatchedExecutor(LocalExecutor()).run(cases)
    alone = LocalExecutor().run(cases)
    assert [r.status for r in batched] == [r.status for r in alone] == ["passed", "engine-failure", "passed"]
    assert [r.exit for r in batched] == [r.exit for r in alone]  # the same code and message
    assert "body `ball` reached a speed above 10000 at t=0.0100 s on fake" in (batched[1].failure or "")
    assert [r.result.steps for r in batched if r.result] == [50, 0, 50]


def test_a_world_the_engine_calls_fatal_does_not_stop_the_others(fall: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from backends.fake import _FakeView

    step = _FakeView.engine_step

    def overflowing(self: _FakeView) -> None:  # world 1 overflows in its 10th step, as numpy reports it
        if self.world.bodies[0].pos[2] == 20.0 and self.steps == 9:
            raise FloatingPointError("overflow encountered in multiply")
        step(self)

    monkeypatch.setattr(_FakeView, "engine_step", overflowing)
    loads = [load_scenario(fall, None, (("params.z0", z),)) for z in (10.0, 20.0, 30.0)]
    results = run_batch(loads, "fake", [None] * 3)
    assert [r.status for r in results] == ["passed", "engine-failure", "passed"]
    assert results[1].failure == "fake (batched): world 1 failed in step 10: overflow encountered in multiply"
    assert results[1].extra["time"] is None and results[1].end_time == pytest.approx(0.09)  # its last good state
    assert [r.end_time for r in results[::2]] == [pytest.approx(0.5)] * 2


def test_a_batch_reports_its_steps(fall: Path) -> None:
    cases = [Case(str(fall), None, "fake", (("params.z0", z),), None) for z in (5.0, 10.0, 20.0)]
    steps: list[tuple[int, int, int]] = []
    started: list[int] = []
    BatchedExecutor(LocalExecutor()).run(cases, None, lambda i, k, n: steps.append((i, k, n)), started.append)
    assert started == [0, 1, 2]  # the batch's cases start together
    assert steps and {i for i, _, _ in steps} == {0} and {n for _, _, n in steps} == {50}
    assert steps[-1][1] == 50 and [k for _, k, _ in steps] == sorted(k for _, k, _ in steps)
    out = io.StringIO()
    bar = BatchProgress(Console(file=out, force_terminal=True, width=120), len(cases))
    with bar:
        BatchedExecutor(LocalExecutor()).run(cases, bar.result, bar.steps, bar.start)
    assert bar.done == 3 and "batch steps" in out.getvalue()


def test_worlds_that_differ_in_structure_are_not_batched(fall: Path) -> None:
    loads = [load_scenario(fall, None, (("params.count", n),)) for n in (1, 1, 3)]
    with pytest.raises(NotBatched, match="variant 2 has 4 bodies, where variant 0 has 2"):
        run_batch(loads, "fake", [None] * 3)
    dt = [load_scenario(fall, None, (("world.dt", d),)) for d in (0.01, 0.02)]
    with pytest.raises(NotBatched, match="dt 0.02 s x 1 substeps, where variant 0 has 0.01 s x 1"):
        run_batch(dt, "fake", [None] * 2)


def test_a_batch_runs_here_not_on_ray(fall: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["sweep", str(fall), "--param", "z0=1,2", "-b", "fake", "--batch", "--executor", "ray",
                 "--out", str(tmp_path)])  # fmt: skip
    assert code == 2 and "`--batch` runs its batches on this machine" in capsys.readouterr().err
    assert not (tmp_path / "sweep.csv").exists()


def test_ctrl_c_finishes_every_variants_trace_as_interrupted(fall: Path, tmp_path: Path) -> None:
    # 10,000 steps each: still running when interrupted
    cases = [Case(str(fall), None, "fake", (("params.z0", z), ("world.duration", 100.0)), str(tmp_path / f"c{z}"))
             for z in (1e4, 2e4)]  # fmt: skip
    seen: dict[int, Any] = {}

    def interrupt(index: int, done: int, total: int) -> None:
        if done >= 20:
            raise KeyboardInterrupt  # what runner.interrupts raises for Ctrl-C

    with pytest.raises(KeyboardInterrupt):
        BatchedExecutor(LocalExecutor()).run(cases, seen.__setitem__, interrupt)
    assert [seen[i].status for i in range(2)] == ["interrupted", "interrupted"]
    for case in cases:
        (trace,) = Path(case.out_dir or "").glob("*.mcap")
        assert read_trace(trace).status == "interrupted" and read_trace(trace).times.size > 20


def test_each_variant_keeps_its_budget(fall: Path, tmp_path: Path) -> None:
    # 100,000 steps of 0.01 s (about 40 s here): after 1 s of stepping each variant's watchdog projects its steps
    # past a 3 s budget and stops it (runner.sim.budget), as it does a separate run, before the job's 3 s limit
    cases = [Case(str(fall), None, "fake", (("params.z0", z), ("world.duration", 1000.0)), None, budget=3.0)
             for z in (1e5, 2e5)]  # fmt: skip
    results = BatchedExecutor(LocalExecutor()).run(cases)
    assert [r.status for r in results] == ["engine-failure", "engine-failure"]
    assert all("over the wall-clock budget of 3 s" in (r.failure or "") for r in results)
    assert all(r.exit.code == 3 for r in results)
