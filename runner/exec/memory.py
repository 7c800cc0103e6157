"""The memory ceiling of a worker process: how much resident memory a case may hold, and how much it holds.

The ceiling is ``SCENARIO_MEMORY_LIMIT``: mebibytes (``4096``), or with a unit (``512M``, ``8G``), or
``off``; default :data:`DEFAULT_MIB`. The parent reads the worker's resident set (its own and that of
the processes it started, such as the trace writer of ``--trace-process``) from ``/proc`` every
:data:`POLL_SECONDS` while a job runs, and kills the worker when it is over (runner.exec.pool).

Why resident memory watched from outside rather than an rlimit set inside: an rlimit's failure is an
allocation that fails somewhere, a ``MemoryError`` anywhere in Python (exit 70, a bug by the one mapping) or
``std::bad_alloc``, an abort, inside an engine (exit 3, "crashed (signal 6)"), never one outcome that names
the limit; and ``RLIMIT_AS`` counts address space that is reserved and not used (measured after a run of
box_pile on DART: VmPeak 494 MB for VmHWM 165 MB; each thread reserves its stack and a malloc arena), so its
value would say little about memory. A kill from the parent is one outcome, ``over memory``, exit 3, with
one message on every path.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from runner.errors import UsageError

__all__ = ["DEFAULT_MIB", "ENV", "MIB", "POLL_SECONDS", "ceiling", "resident"]

ENV = "SCENARIO_MEMORY_LIMIT"
MIB = 1024 * 1024
#: the default: about 25 times the largest worker measured on the repository's scenarios (167 MB, DART)
DEFAULT_MIB = 4096
#: seconds between two readings of a busy worker's resident memory
POLL_SECONDS = 0.05
_VALUE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*([MmGg]i?[Bb]?)?\s*$")
_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096


def ceiling(text: str | None = None) -> int | None:
    """The ceiling in bytes from ``text`` (default: the environment's ``SCENARIO_MEMORY_LIMIT``); None: off."""
    text = os.environ.get(ENV, "") if text is None else text
    if not text.strip():
        return DEFAULT_MIB * MIB
    if text.strip().lower() in ("off", "0", "none"):
        return None
    match = _VALUE.match(text)
    if match is None or float(match.group(1)) <= 0:
        raise UsageError(f"Invalid `{ENV}`. Expected mebibytes (4096), a size with M or G (8G), or off. "
                         f"Received: {text!r}")  # fmt: skip
    unit = (match.group(2) or "M")[0].upper()
    return int(float(match.group(1)) * MIB * (1024 if unit == "G" else 1))


def _children(pid: int) -> list[int]:
    try:
        return [int(p) for p in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except (OSError, ValueError):
        return []


def resident(pid: int) -> int | None:
    """Bytes resident in ``pid`` and the processes it started; None where ``/proc`` cannot tell (not Linux,
    or the process is gone)."""
    total, seen, todo = 0, set(), [pid]
    while todo:
        one = todo.pop()
        if one in seen:
            continue
        seen.add(one)
        try:
            fields = Path(f"/proc/{one}/statm").read_text().split()
        except OSError:
            if one == pid:
                return None
            continue
        total += int(fields[1]) * _PAGE
        todo.extend(_children(one))
    return total
