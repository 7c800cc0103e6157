"""The switch between the bounded run (``make test``) and the long run (``make fuzz``).

``FUZZ_CASES`` sets how many hostile documents the loader fuzzing generates (default 200, about 5 s);
``FUZZ_STRUCTURED`` how many grammar-aware mutants of valid scenarios it generates (default 200);
``FUZZ_FAULTS`` how many signals are sent at random moments to running ``scenario run`` processes
(default 2); ``FUZZ_FILES`` how many model files, WAVs, golden files and traces each (default 50);
``FUZZ_COMMAND_EVERY`` which share of the fuzzed files and mutants also goes through the command in a
subprocess (default one in 100, the first included: tests/reliability/sampled.py); ``FUZZ_SEED`` varies
the generated cases (default: hypothesis's fixed derandomized seed, so that a run is reproducible).
``make fuzz`` sets ``FUZZ_CASES=20000 FUZZ_STRUCTURED=20000 FUZZ_FILES=5000 FUZZ_FAULTS=200
FUZZ_CONCURRENT=20``. The counts are printed at the end of the session.
"""

from __future__ import annotations

import os
import signal
from collections import Counter
from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import HealthCheck, seed, settings

if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    # started in the background by a non-interactive shell (`make fuzz &`, nohup): the commands under test would
    # inherit SIGINT ignored and, as POSIX asks of a background job's programs (runner.interrupts.install), keep
    # ignoring it; a handler here is reset to the default in them at exec, as a terminal gives it
    signal.signal(signal.SIGINT, signal.default_int_handler)

FUZZ_CASES = int(os.environ.get("FUZZ_CASES", "200"))
FUZZ_STRUCTURED = int(os.environ.get("FUZZ_STRUCTURED", "200"))
FUZZ_FAULTS = int(os.environ.get("FUZZ_FAULTS", "2"))
FUZZ_SEED = os.environ.get("FUZZ_SEED")

#: outcome -> count, per fuzzing test; printed in the terminal summary
STATS: dict[str, Counter[str]] = {}


def fuzz_settings(cases: int) -> Callable[[Any], Any]:
    """Hypothesis settings for a fuzzing test: ``cases`` examples, reproducible unless FUZZ_SEED is set."""
    chosen = settings(
        max_examples=cases,
        deadline=None,
        derandomize=FUZZ_SEED is None,
        database=None,
        print_blob=True,
        suppress_health_check=list(HealthCheck),
    )

    def apply(test: Any) -> Any:
        test = chosen(test)
        return seed(int(FUZZ_SEED))(test) if FUZZ_SEED is not None else test

    return apply


def count(test: str, outcome: str) -> None:
    STATS.setdefault(test, Counter())[outcome] += 1


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if not STATS:
        return
    terminalreporter.section("reliability figures")
    for test, outcomes in sorted(STATS.items()):
        parts = ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items()))
        terminalreporter.write_line(f"{test}: {sum(outcomes.values())} cases ({parts})")
