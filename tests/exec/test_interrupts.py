"""Ctrl-C during a batch on the local pool: the finished cases keep their whole traces, the running ones
finish theirs as interrupted, and nothing more starts (the Ray side: tests/exec/test_ray_cluster.py).

Eight 0.3 s box columns on PyBullet with two workers, interrupted after the second result; about 3 s.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from reports.trace_reader import read_trace
from runner.exec.executors import Case, LocalExecutor

ROOT = Path(__file__).resolve().parents[2]
PILE = ROOT / "scenarios" / "box_pile.yaml"


def cases(out: Path, n: int) -> list[Case]:
    return [Case(str(PILE), None, "pybullet", (("world.duration", 0.3), ("params.count", 2 + k % 3)),
                 str(out / f"c{k:02d}")) for k in range(n)]  # fmt: skip


def interrupt_after(k: int, seen: dict[int, Any]) -> Any:
    """An on_result that records each result and raises Ctrl-C's KeyboardInterrupt at the k-th."""

    def on_result(index: int, result: Any) -> None:
        seen[index] = result
        if len(seen) == k:
            raise KeyboardInterrupt  # what runner.interrupts raises for Ctrl-C

    return on_result


def test_ctrl_c_on_the_local_pool_finishes_the_running_traces_and_starts_nothing_more(tmp_path: Path) -> None:
    batch = cases(tmp_path, 8)
    seen: dict[int, Any] = {}
    with pytest.raises(KeyboardInterrupt):
        LocalExecutor(2).run(batch, interrupt_after(2, seen))
    finished = [k for k, r in seen.items() if r.status in ("passed", "failed")]
    stopped = [k for k, r in seen.items() if r.status == "interrupted"]
    # the case still running at Ctrl-C (two workers: one) ends as interrupted, or finished if it got there first
    assert 2 <= len(finished) and len(seen) == len(finished) + len(stopped) <= 3
    for k, case in enumerate(batch):
        files = sorted(Path(case.out_dir or "").glob("*.mcap*"))
        if k in finished:  # finished before Ctrl-C: its whole trace
            assert [read_trace(f).status for f in files] == [seen[k].status]
        elif k in stopped:  # running: its trace finished as interrupted (none if it had not built its world yet)
            assert [read_trace(f).status for f in files] in ([], ["interrupted"])
        else:  # never started
            assert not Path(case.out_dir or "").exists(), k
