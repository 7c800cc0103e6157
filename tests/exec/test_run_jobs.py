"""`scenario run -j N`: folders of files, cases in parallel, the same output and traces as one by one.

The three example scenarios (9 cases) on PyBullet, then a crashing engine; about 8 s.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from runner.cli.main import main

ROOT = Path(__file__).resolve().parents[2]


def test_jobs_give_the_same_results_and_traces(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    files = [str(p) for p in sorted((ROOT / "scenarios").glob("*.yaml"))]  # a folder would recurse: 31 cases
    assert main(["run", *files, "--all-variants", "-q", "--out", str(tmp_path / "one")]) == 0
    serial = capsys.readouterr().out
    assert main(["run", *files, "--all-variants", "-q", "-j", "2", "--out", str(tmp_path / "two")]) == 0
    parallel = capsys.readouterr().out
    assert "9/9 runs passed" in serial and serial == parallel
    names = sorted(p.name for p in (tmp_path / "one").glob("*.mcap"))
    assert len(names) == 9 and names == sorted(p.name for p in (tmp_path / "two").glob("*.mcap"))
    for name in names:
        assert (tmp_path / "two" / name).read_bytes() == (tmp_path / "one" / name).read_bytes()


def test_a_crashed_worker_is_an_engine_failure(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pile = str(ROOT / "scenarios" / "box_pile.yaml")
    code = main(["run", pile, pile, "-b", "crash", "-j", "2", "--no-trace", "--set", "world.duration=0.5"])
    assert code == 3
    assert capsys.readouterr().out.count("crashed") >= 2
