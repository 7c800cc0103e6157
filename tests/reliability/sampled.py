"""A sample of the fuzzed cases through the command itself, as a user runs it (issue 31, item 8).

The fuzzers check each case in their own process (fast: about 10-50 ms a case); one case in
``FUZZ_COMMAND_EVERY`` (default 100) of each kind, the first one included, is also given to ``scenario``
in a subprocess, so that the exit code is the one a user gets: never 70, no traceback, an exit 2 whose
message names the file with a line (or, for a trace, names it; or, for a feature the engine lacks, names
the feature and the engine); the command within its time (a run: its
budget, ``--timeout``, plus the grace before SIGKILL and the interpreter's start); the peak resident
memory of the command and of its workers (tests/reliability/memory.py) under the worker's memory ceiling
(runner/exec/memory.py; for a worker, plus what it may gain between two readings).
"""

from __future__ import annotations

import os
import re
from collections import Counter
from pathlib import Path

from runner.exec import memory
from runner.exec.pool import TIMEOUT_GRACE

from .conftest import STATS, count
from .memory import run_measured
from .processes import environment

EVERY = int(os.environ.get("FUZZ_COMMAND_EVERY", "100"))
#: seconds for the interpreter to start and import the runner and an engine, measured at 2-4 s on the shared
#: 2-core machine; ten times that
STARTUP_SECONDS = 30.0
#: what a worker may hold past the ceiling before it is killed (tests/reliability/test_memory_ceiling.py)
OVERSHOOT_MIB = 512
#: `run`'s and `validate`'s refusal of what the file legitimately holds and the engine lacks (docs/reliability.md's
#: exit-code table, "capability refused"): it names the feature and the engine, and (in parentheses) what in a
#: robot's model file needs it, at the model file's line
CAPABILITY = re.compile(r"needs [\w:, -]+(?: \(.*?\))?, which backend `[\w-]+` does not support")
_SEEN: Counter[str] = Counter()
_PEAKS: dict[str, list[float]] = {}


def due(kind: str) -> bool:
    """Whether this case of ``kind`` goes through the command too (the 1st, the EVERY+1-th, ...)."""
    _SEEN[kind] += 1
    return (_SEEN[kind] - 1) % EVERY == 0


def through_command(kind: str, args: list[str], *places: Path, how: str, budget: float = 0.0,
                    lines: bool = True, cwd: Path | None = None) -> int:  # fmt: skip
    """``scenario ARGS`` under the checks of the module docstring; its exit code. ``places``: the files an
    exit-2 message may name (with ``:line`` when ``lines``); ``budget``: the run's time limit, if it runs."""
    limit = budget + (TIMEOUT_GRACE if budget else 0.0) + STARTUP_SECONDS
    found = run_measured(args, environment(), timeout=limit + 60.0, cwd=cwd)
    said = found.stdout + found.stderr
    where = f"`scenario {' '.join(args)[:200]}` for {how}"
    assert found.code != 70, f"exit 70 from {where}: {said[-1500:]}"
    assert "Traceback" not in said, f"a traceback from {where}: {said[-1500:]}"
    capability = CAPABILITY.search(said) is not None  # refused naming the feature and the engine: no line to give
    if found.code == 2 and not capability:
        pattern = "|".join(re.escape(str(p)) + (r":\d+" if lines else "") for p in places)
        assert re.search(pattern, said), f"an exit-2 message not naming the file from {where}: {said[-1500:]}"
    assert found.seconds < limit, f"{found.seconds:.1f} s (over {limit:g} s) for {where}"
    ceiling = (memory.ceiling() or 0) / memory.MIB
    if ceiling:
        assert found.command_mib < ceiling, f"the command held {found.command_mib:.0f} MiB for {where}"
        assert found.workers_mib < ceiling + OVERSHOOT_MIB, f"a worker held {found.workers_mib:.0f} MiB for {where}"
    lacks = " (a capability the engine lacks)" if capability else ""
    count(f"{kind} through the command", f"exit {found.code}{lacks}")
    peaks = _PEAKS.setdefault(kind, [])
    peaks.append(max(found.command_mib, found.workers_mib))
    STATS[f"{kind} through the command, memory"] = Counter({f"largest peak {max(peaks):.0f} MiB "
                                                            f"(ceiling {ceiling:.0f} MiB)": len(peaks)})  # fmt: skip
    return found.code
