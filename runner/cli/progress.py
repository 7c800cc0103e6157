"""A progress bar for commands that run many cases (``run`` with several cases, ``sweep``): cases done out
of all, running, failed, elapsed and an estimate of the time left, on stderr.

It shows only on a terminal and never under ``--quiet`` or ``--json`` (:func:`wanted`); a redirected
stderr gets nothing. The bar is transient: it goes away when the batch ends, leaving the command's own
output. Failed means any case that did not pass (an assertion failed, an engine failed or crashed, bad
input in that case).
"""

from __future__ import annotations

from collections.abc import Callable
from types import TracebackType
from typing import TYPE_CHECKING

from rich.console import Console

from runner.exec.cases import CaseResult

if TYPE_CHECKING:
    from rich.progress import TaskID

__all__ = ["BatchProgress", "wanted"]


def wanted(err: Console, quiet: bool, json: bool) -> bool:
    """A bar only for a person watching: stderr a terminal, and neither ``--quiet`` nor ``--json``."""
    return err.is_terminal and not (quiet or json)


class BatchProgress:
    """The executors' callbacks (``on_start``, ``on_result``) kept as counts and shown as a rich bar.
    ``result`` then calls ``then`` (the command's own ``on_result``), if given."""

    def __init__(self, err: Console, total: int, label: str = "cases",
                 then: Callable[[int, CaseResult], None] | None = None) -> None:  # fmt: skip
        # imported here: a command that shows no bar (--quiet, --json, no terminal) does not import it
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.total = total
        self.then = then
        self.running: set[int] = set()
        self.done = 0
        self.failed = 0
        self._progress = Progress(
            TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("running {task.fields[running]}, [red]failed {task.fields[failed]}[/]"),
            TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
            console=err, transient=True, refresh_per_second=4,
        )  # fmt: skip
        self._task: TaskID = self._progress.add_task(label, total=total, running=0, failed=0)
        self._steps: TaskID | None = None  # a batched run's steps (steps())

    def start(self, index: int) -> None:
        self.running.add(index)
        self._show()

    def result(self, index: int, res: CaseResult) -> None:
        self.running.discard(index)
        self.done += 1
        self.failed += res.status != "passed"
        self._show()
        if self.then is not None:
            self.then(index, res)

    def steps(self, index: int, done: int, total: int) -> None:
        """A batch's progress (``on_progress``: a batched sweep runs many cases in one job): its steps done."""
        if self._steps is None:
            self._steps = self._progress.add_task("batch steps", total=total, running=len(self.running), failed=0)
        self._progress.update(self._steps, completed=done, total=total)

    def _show(self) -> None:
        self._progress.update(self._task, completed=self.done, running=len(self.running), failed=self.failed)

    def __enter__(self) -> BatchProgress:
        self._progress.start()
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:  # fmt: skip
        self._progress.stop()
