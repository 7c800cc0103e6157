"""The wall-clock budget of a run: stop it at a step boundary when it is over, or when its cost per step
says it will be, instead of leaving it to run for hours (10,000 coincident bodies cost seconds per step).

The budget counts from the start of the run (importing the engine and building the world included).
After each step the watchdog compares the time spent with the budget, and, once three steps and one
second of stepping have been measured, the time the remaining steps will take at the mean cost per step
so far. Either going over raises :class:`~runner.errors.BudgetExceeded` (an engine failure, exit 3)
naming the cost per step; the trace is finished up to the last step, status ``engine-failure``.
A step that never returns is the parent's business: it stops the process at the budget (``timed out``).
"""

from __future__ import annotations

import math
import time

from runner.errors import BudgetExceeded

__all__ = ["DEFAULT_BUDGET", "Watchdog", "duration_text"]

#: seconds a run may take when neither the scenario (``world.budget``) nor the command (``--timeout``) says
DEFAULT_BUDGET = 3600.0
MIN_STEPS = 3  # steps measured before a projection is trusted (the first ones pay for warm-up)
MIN_SECONDS = 1.0  # seconds of stepping measured before a projection is trusted


def duration_text(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "forever"
    if seconds < 120:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"


class Watchdog:
    """Checks one run's budget after each step (see the module docstring)."""

    def __init__(self, budget: float, steps: int, dt: float, started: float, backend: str) -> None:
        self.budget = budget
        self.steps = steps
        self.dt = dt
        self.started = started
        self.backend = backend
        self.loop_start = time.perf_counter()

    def check(self, done: int) -> None:
        """``done`` steps of ``steps`` are finished."""
        now = time.perf_counter()
        spent = now - self.started
        stepping = now - self.loop_start
        per_step = stepping / done if done else math.inf
        if spent > self.budget:
            self._stop(done, per_step, spent, f"it has run for {duration_text(spent)}")
        if done >= MIN_STEPS and stepping >= MIN_SECONDS:
            projected = spent + per_step * (self.steps - done)
            if projected > self.budget:
                self._stop(done, per_step, projected, f"its {self.steps} steps would take about "
                           f"{duration_text(projected)}")  # fmt: skip

    def _stop(self, done: int, per_step: float, total: float, what: str) -> None:
        raise BudgetExceeded(
            f"stopped at t={done * self.dt:.4f} s on {self.backend}: each step costs {per_step:.3g} s of wall "
            f"time (mean of {done}), and {what}, over the wall-clock budget of {duration_text(self.budget)} "
            "(world.budget; --timeout overrides it)",
            backend=self.backend,
            time=done * self.dt,
        )
