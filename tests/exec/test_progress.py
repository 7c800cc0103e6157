"""The batch progress bar (runner/cli/progress.py): its counts follow the executor's callbacks, it shows on
a terminal, and it is silent when stderr is not one and under --quiet. Short PyBullet piles; about 6 s."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

from rich.console import Console

from runner.cli.progress import BatchProgress
from runner.exec.executors import Case, LocalExecutor
from tests.engines import INSTALLED

ROOT = Path(__file__).resolve().parents[2]
PILE = str(ROOT / "scenarios" / "box_pile.yaml")


def test_the_counts_follow_the_cases(tmp_path: Path) -> None:
    cases = [Case(PILE, None, "pybullet", (("world.duration", 0.2), ("params.count", n)), None) for n in (1, 2)]
    cases.append(Case(PILE, None, "nope", (), None))  # an unknown backend: a failed case
    out = io.StringIO()
    seen: list[tuple[int, int, int]] = []
    bar = BatchProgress(Console(file=out, force_terminal=True, width=120), len(cases))

    def after(index: int, res: object) -> None:
        seen.append((bar.done, len(bar.running), bar.failed))

    bar.then = after
    with bar:
        LocalExecutor(2).run(cases, bar.result, None, bar.start)
    assert bar.done == 3 and not bar.running
    assert bar.failed == 3  # 0.2 s piles do not settle, and the unknown backend is an error
    assert [d for d, _, _ in seen] == [1, 2, 3] and max(r for _, r, _ in seen) <= 2
    assert "running" in out.getvalue() and "failed" in out.getvalue()


def _run(*extra: str, terminal: bool) -> str:
    env = {k: v for k, v in os.environ.items() if k not in ("FORCE_COLOR", "TTY_COMPATIBLE", "NO_COLOR")}
    if terminal:
        env["FORCE_COLOR"] = "1"  # rich treats the pipe as a terminal
    two = ",".join(INSTALLED[:2])  # any two engines: the bar counts cases
    cmd = [str(Path(sys.executable).with_name("scenario")), "run", PILE, "--all-variants", "-b", two,
           "--no-trace", "--set", "world.duration=0.2", "-j", "2", *extra]  # fmt: skip
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120).stderr


def test_the_bar_shows_on_a_terminal_only_and_not_under_quiet() -> None:
    assert "ETA" in _run(terminal=True)
    assert "ETA" not in _run(terminal=False)
    assert "ETA" not in _run("--quiet", terminal=True)
