"""Which event deliveries the trace's /log shows one by one, and the line that sums up the rest.

An event that is delivered again on the next step (or on the same one) after its previous delivery, with
the same name and source, continues a *run*: an input with ``repeat: {every: dt}``, a handler's event
raised every step. The Log shows a run's first delivery as any other (``tick (input)``) and, once the run
has ended, one line for it (``tick (input) fired 5000 times, on every step from 0 s to 9.998 s``), stamped
at the first step it was no longer delivered on (never before a message already written: the Log stays in
time order). A run that lasts to the end of the trace is summed up at the end, before the verdicts'
summary. /events keeps every delivery, with its detail: the reports, the golden files and the State
Transitions panel read it, not the Log.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["EventRuns", "seconds_text"]


@dataclass
class _Run:
    """A run of deliveries of one event: its first and last time and how many."""

    first_ns: int
    last_ns: int
    count: int


class EventRuns:
    """The runs of events being delivered, for a trace whose step is ``dt`` seconds."""

    def __init__(self, dt: float) -> None:
        self._step_ns = max(1, round(dt * 1e9))
        self._runs: dict[tuple[str, str], _Run] = {}

    def _continues(self, run: _Run, ns: int) -> bool:
        """``ns`` is on the step after the run's last delivery or on the same step (half a step of slack
        absorbs the nanosecond rounding of ``k * dt``)."""
        return 2 * (ns - run.last_ns) <= 3 * self._step_ns

    def deliver(self, ns: int, name: str, source: str) -> bool:
        """Note a delivery at ``ns``; True when the Log shows it (it starts a run). Call :meth:`ended`
        with ``ns`` first, so that a run that ended before it is summed up before it starts a new one."""
        key = (name, source)
        run = self._runs.get(key)
        if run is not None and self._continues(run, ns):
            run.last_ns = ns
            run.count += 1
            return False
        self._runs[key] = _Run(ns, ns, 1)
        return True

    def ended(self, ns: int, written_ns: int, everything: bool = False) -> list[tuple[int, str]]:
        """The summaries of the runs that cannot continue at ``ns`` (every run with ``everything``), as
        (time, text), in time order; ``written_ns`` is the latest time already written. A run of one
        delivery has nothing to sum up."""
        if not self._runs:  # every step asks; mostly no event is being delivered
            return []
        out: list[tuple[int, str]] = []
        for key, run in list(self._runs.items()):
            if not everything and self._continues(run, ns):
                continue
            del self._runs[key]
            if run.count > 1:
                stamp = max(run.last_ns + self._step_ns, written_ns)
                if everything:
                    stamp = min(stamp, max(ns, written_ns))
                out.append((stamp, _summary(key, run)))
        return sorted(out)


def seconds_text(ns: int) -> str:
    """Simulated seconds as the Log prints them: 0, 0.002, 9.998 (exact to the nanosecond)."""
    text = f"{ns / 1e9:.9f}".rstrip("0").rstrip(".")
    return text or "0"


def _summary(key: tuple[str, str], run: _Run) -> str:
    name, source = key
    return (f"{name} ({source}) fired {run.count} times, on every step from {seconds_text(run.first_ns)} s"
            f" to {seconds_text(run.last_ns)} s")  # fmt: skip
