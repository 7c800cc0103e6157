"""runner.exec.executors: the local pool gives what one process gives, and crashes and errors stay contained.

The cases are short box piles on PyBullet (0.3 s, 30 steps): the tests check the executors, not the engine.
About 6 s in all (the pool forks two workers per test).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from backends.errors import UnknownBackend
from runner.errors import UsageError
from runner.exec.executors import Case, LocalExecutor, estimate_cost, make_executor
from runner.exec.pool import Job, schedule
from runner.language.load import load_scenario

ROOT = Path(__file__).resolve().parents[2]
PILE = str(ROOT / "scenarios" / "box_pile.yaml")
SHORT = (("world.duration", 0.3),)


def pile_cases(out: Path, counts: tuple[int, ...] = (2, 3, 4)) -> list[Case]:
    return [Case(PILE, None, "pybullet", (*SHORT, ("params.count", n)), str(out / f"n{n}")) for n in counts]


def summary(results: list) -> list[tuple]:
    return [(r.status, [v.as_dict() for v in r.result.verdicts], r.result.end_time) for r in results]


def test_pool_gives_the_same_results_and_traces_as_one_process(tmp_path: Path) -> None:
    serial = LocalExecutor(1).run(pile_cases(tmp_path / "serial"))
    pooled = LocalExecutor(2).run(pile_cases(tmp_path / "pool"))
    assert summary(serial) == summary(pooled)
    for a, b in zip(serial, pooled, strict=True):
        assert Path(a.result.trace).read_bytes() == Path(b.result.trace).read_bytes()  # deterministic, byte for byte
    # results come back in the order given, whatever order they finish in
    assert [r.case.overrides[-1] for r in pooled] == [("params.count", n) for n in (2, 3, 4)]


def test_a_crashing_engine_is_reported_and_the_other_cases_finish(tmp_path: Path) -> None:
    cases = pile_cases(tmp_path, (2,))
    cases.insert(0, Case(PILE, None, "crash", SHORT + (("backend_options.crash.after_steps", 3),), None))
    cases.append(Case(PILE, None, "nope", SHORT, None))
    seen: list[int] = []
    results = LocalExecutor(2).run(cases, lambda i, r: seen.append(i))
    assert [r.status for r in results] == ["crashed", "failed", "error"]
    assert results[0].label == "crashed (signal 11)" and results[0].exit.code == 3
    assert sorted(seen) == [0, 1, 2]
    assert results[2].error_type == "UnknownBackend"
    with pytest.raises(UnknownBackend, match="nope"):
        results[2].raise_error()
    # the short pile did not settle within 0.3 s: its one failed assertion is the settling window
    assert [v.name for v in results[1].result.verdicts if not v.passed] == ["pile-settles"]


def test_costly_cases_start_first_and_results_keep_their_order() -> None:
    short = load_scenario(Path(PILE), None, SHORT)
    long = load_scenario(Path(PILE), None, (("world.duration", 3.0), ("params.count", 9)))
    assert estimate_cost(short) == 30 * (5 + 2)  # steps x (bodies + 1)
    assert estimate_cost(long) == 300 * (9 + 2)
    jobs = [Job(dict, (), cost=c) for c in (1.0, 5.0, 3.0, 5.0)]
    stack = schedule(jobs)
    assert [stack.pop() for _ in range(4)] == [1, 3, 2, 0]  # costliest first, ties in order


def test_executor_choice_is_checked() -> None:
    with pytest.raises(UsageError, match="--ray-address"):
        make_executor("local", 2, "auto")
    with pytest.raises(UsageError, match="executor"):
        make_executor("slurm", 2)
    with pytest.raises(UsageError, match="-j"):
        LocalExecutor(0)

