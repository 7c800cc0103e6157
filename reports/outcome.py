"""How an isolated run's process ended, when its trace cannot say so: the outcome file beside the trace.

A run whose child process crashed, hung or could not start leaves no ``result`` record in its trace
(only a ``.mcap.partial``, or nothing at all). The parent (:mod:`runner.exec.cases`) then writes
``<scenario>__<variant>__<backend>.outcome.json`` next to where the trace belongs (as the runner keeps a
run's wall-clock cost in ``<...>.cost.json``), so that a report rebuilt from the files alone
(``scenario report``) says "crashed (signal 11)" exactly as the comparison that ran it did. A run that
finished normally has no outcome file: its trace says everything.

The file holds only what the parent observed about the process (never a wall-clock time).
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any, Final

from reports.trace_format import FILE_SUFFIX, PARTIAL_SUFFIX

__all__ = [
    "COST_SUFFIX",
    "CRASHED",
    "ERROR",
    "EXITED",
    "INTERRUPTED",
    "OUTCOMES",
    "OVER_MEMORY",
    "OUTCOME_SUFFIX",
    "TIMED_OUT",
    "RunOutcome",
    "cost_path",
    "outcome_path",
    "read_outcome",
    "trace_key",
    "write_outcome",
]

OUTCOME_SUFFIX: Final = ".outcome.json"
OUTCOME_FORMAT: Final = 1

#: killed by a signal it did not ask for (a segfault, SIGKILL from outside)
CRASHED: Final = "crashed"
#: still running at the time limit; stopped with SIGTERM, then SIGKILL after a grace period
TIMED_OUT: Final = "timed-out"
#: its resident memory went over the worker's ceiling (SCENARIO_MEMORY_LIMIT); stopped with SIGKILL at once
OVER_MEMORY: Final = "over-memory"
#: exited with a non-zero code without reporting a result
EXITED: Final = "exited"
#: refused or failed before or while running, with a message (bad input, missing engine, unsupported feature)
ERROR: Final = "error"
#: stopped by SIGINT or SIGTERM from outside (the trace is finished and marked interrupted)
INTERRUPTED: Final = "interrupted"
OUTCOMES: Final = frozenset({CRASHED, TIMED_OUT, OVER_MEMORY, EXITED, ERROR, INTERRUPTED})


@dataclass(frozen=True)
class RunOutcome:
    """How a case's process ended when its trace cannot say (the ``.outcome.json`` beside it)."""

    scenario: str
    variant: str
    backend: str
    backend_version: str
    outcome: str  # one of OUTCOMES
    signal: int | None = None  # the signal that ended the process, if one did
    returncode: int | None = None
    timeout: float | None = None  # seconds, for timed-out
    message: str = ""  # the child's error, or the tail of its output
    trace: str | None = None  # file name of the trace beside this file (final or .partial), if any

    @property
    def label(self) -> str:
        """The one-line status a report shows: "crashed (signal 11)", "timed out", ..."""
        if self.outcome == CRASHED:
            return f"crashed (signal {self.signal})"
        if self.outcome == TIMED_OUT:
            return "timed out"
        if self.outcome == OVER_MEMORY:
            return "over memory"
        if self.outcome == EXITED:
            return f"exited with code {self.returncode}"
        if self.outcome == INTERRUPTED:
            return "interrupted"
        return "error"

    @property
    def detail(self) -> str:
        """What the label leaves out: the time limit, the signal that stopped a hung run, the message."""
        parts = []
        if self.outcome == TIMED_OUT and self.timeout is not None:
            parts.append(f"no result after {self.timeout:g} s")
            if self.signal is not None:
                parts.append(f"stopped by signal {self.signal}")
        if self.message:
            parts.append(self.message)
        return "; ".join(parts)

    def to_json(self) -> dict[str, Any]:
        return {"format": OUTCOME_FORMAT, **asdict(self)}


COST_SUFFIX: Final = ".cost.json"  # written by runner.sim.run.write_cost beside a finished trace


def trace_key(path: Path) -> Path | None:
    """The final trace path a run's file belongs to: ``X.mcap`` for ``X.mcap``, ``X.mcap.partial``,
    ``X.outcome.json`` and ``X.cost.json``; None for any other file."""
    name = path.name
    if name.endswith(FILE_SUFFIX):
        return path
    if name.endswith(FILE_SUFFIX + PARTIAL_SUFFIX):
        return path.with_name(name[: -len(PARTIAL_SUFFIX)])
    for suffix in (OUTCOME_SUFFIX, COST_SUFFIX):
        if name.endswith(suffix) and len(name) > len(suffix):
            return path.with_name(name[: -len(suffix)] + FILE_SUFFIX)
    return None


def _beside(trace: Path, suffix: str) -> Path:
    key = trace_key(trace) or trace
    return key.with_name(key.name.removesuffix(FILE_SUFFIX) + suffix)


def outcome_path(trace: Path) -> Path:
    """Where the outcome file of the run whose (final or partial) trace is ``trace`` lives."""
    return _beside(trace, OUTCOME_SUFFIX)


def cost_path(trace: Path) -> Path:
    """Where the runner keeps the wall-clock cost of the run whose trace is ``trace``."""
    return _beside(trace, COST_SUFFIX)


def write_outcome(path: Path, outcome: RunOutcome) -> Path:
    """Write ``outcome`` to ``path`` atomically (a temporary name, then a rename)."""
    if outcome.outcome not in OUTCOMES:
        raise ValueError(f"unknown outcome {outcome.outcome!r}; expected one of {sorted(OUTCOMES)}")
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(json.dumps(outcome.to_json(), indent=2, sort_keys=True) + "\n", encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)  # a full disk leaves nothing half-written behind
        raise
    return path


def read_outcome(path: Path) -> RunOutcome:
    """Read an outcome file; ``ValueError`` when it is not one."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path} is not a readable outcome file: {exc}") from exc
    if not isinstance(data, dict) or data.get("format") != OUTCOME_FORMAT or data.get("outcome") not in OUTCOMES:
        raise ValueError(f"{path} is not an outcome file (format {OUTCOME_FORMAT})")
    names = {f.name for f in fields(RunOutcome)}
    try:
        return RunOutcome(**{k: v for k, v in data.items() if k in names})
    except TypeError as exc:
        raise ValueError(f"{path} is missing fields of an outcome file: {exc}") from exc
