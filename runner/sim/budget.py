"""The wall-clock budget of a run: stop it at a step boundary when it is over, or when its cost per step
says it will be, instead of leaving it to run for hours (10,000 coincident bodies cost seconds per step).

The budget counts from the start of the run (importing the engine and building the world included).
After each step the watchdog compares the time spent with the budget, and, once a second of stepping
after the first step has been measured, the time the remaining steps will take at the recent cost per
step. Either going over raises :class:`~runner.errors.BudgetExceeded` (an engine failure, exit 3)
naming the cost per step; the trace is finished up to the last step, status ``engine-failure``.
A step that never returns is the parent's business: it stops the process at the budget (``timed out``).
"""

from __future__ import annotations

import math
import time
from collections import deque

from runner.errors import BudgetExceeded

__all__ = ["DEFAULT_BUDGET", "Watchdog", "duration_text"]

#: seconds a run may take when neither the scenario (``world.budget``) nor the command (``--timeout``) says
DEFAULT_BUDGET = 3600.0
MIN_SECONDS = 1.0  # seconds of stepping a projection is based on (at least one step, the first excluded)
_SAMPLE_EVERY = 0.2  # seconds between the (time, steps) samples the cost per step is measured between


def duration_text(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "forever"
    if seconds < 120:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"


class Watchdog:
    """Checks one run's budget after each step (see the module docstring).

    The cost per step is measured over the last second or so of stepping (between samples taken every
    0.2 s), never over the first step, which pays for warm-up (DART's first step of 1000 coincident
    spheres: 2.3 s, then 0.1 s): a slow start does not condemn a run whose steps are cheap."""

    def __init__(self, budget: float, steps: int, dt: float, started: float, backend: str) -> None:
        self.budget = budget
        self.steps = steps
        self.dt = dt
        self.started = started
        self.backend = backend
        self._samples: deque[tuple[float, int]] = deque()

    def check(self, done: int) -> None:
        """``done`` steps of ``steps`` are finished."""
        now = time.perf_counter()
        spent = now - self.started
        samples = self._samples
        if not samples or now - samples[-1][0] >= _SAMPLE_EVERY:
            samples.append((now, done))
        while len(samples) > 1 and samples[1][0] <= now - MIN_SECONDS:
            samples.popleft()
        base_t, base_done = samples[0]
        per_step = (now - base_t) / (done - base_done) if done > base_done else math.nan
        if spent > self.budget:
            self._stop(done, per_step, f"it has run for {duration_text(spent)}")
        if done > base_done and now - base_t >= MIN_SECONDS:
            projected = spent + per_step * (self.steps - done)
            if projected > self.budget:
                self._stop(done, per_step, f"its {self.steps} steps would take about {duration_text(projected)}")

    def _stop(self, done: int, per_step: float, what: str) -> None:
        cost = f"each step costs {per_step:.3g} s of wall time" if math.isfinite(per_step) else "its steps are slow"
        raise BudgetExceeded(
            f"stopped at t={done * self.dt:.4f} s on {self.backend}: {cost}, and {what}, over the wall-clock "
            f"budget of {duration_text(self.budget)} (world.budget; --timeout overrides it)",
            backend=self.backend,
            time=done * self.dt,
        )
