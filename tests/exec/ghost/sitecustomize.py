"""On PYTHONPATH (tests/exec/exit_table.py, tests/reliability), with SCENARIO_GHOST_BACKEND=1: two test-only
backends, registered in every process that starts with this environment (the command, its worker
processes, the workers of a Ray cluster started with it):

* ``ghost``: an engine that is found but cannot be imported, as after a broken install;
* ``slowimport``: the fake backend behind an engine module that takes 2 s to import and, like a pybind11
  module's initialisation, turns any exception raised meanwhile into ImportError (``slow_engine.py``);
* ``buggy``: the fake backend with a bug: its third step raises TypeError (``buggy_engine.py``).
"""

from __future__ import annotations

import os

if os.environ.get("SCENARIO_GHOST_BACKEND") == "1":
    from backends import registry

    registry._KNOWN["ghost"] = registry.BackendEntry(
        "ghost", "ghost_engine:GhostBackend", "json", "ghost-engine", "ghost",
        "test-only: an engine that cannot be imported", hidden=True,
    )  # fmt: skip
    registry._KNOWN["slowimport"] = registry.BackendEntry(
        "slowimport", "slow_engine:SlowImportBackend", "slow_engine", "slow-engine", "slowimport",
        "test-only: an engine that takes 2 s to import", hidden=True,
    )  # fmt: skip
    registry._KNOWN["buggy"] = registry.BackendEntry(
        "buggy", "buggy_engine:BuggyBackend", "json", "buggy-engine", "buggy",
        "test-only: an adapter with a bug", hidden=True,
    )  # fmt: skip
