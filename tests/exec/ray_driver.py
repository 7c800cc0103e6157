"""The driver of tests/exec/test_ray_cluster.py: ``scenario sweep ... --executor ray`` in a process of its
own (the cluster's token in its environment, and no Ray state left in the test's process), with a hook on
the results as they come back:

``python -m tests.exec.ray_driver kill N MARKER -- SWEEP ARGS``: after the N-th result (and each one
after it until it succeeds), SIGKILL one Ray worker process of the node whose processes carry MARKER
while it runs a case;
``python -m tests.exec.ray_driver interrupt N - -- SWEEP ARGS``: after the N-th result, SIGINT to itself
(a Ctrl-C at the terminal).

Prints one JSON line: the exit code, the cases retried, the pids killed, the results seen (index: status)
and the sweep's wall seconds.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time
from typing import Any

from runner.cli.main import main
from runner.exec.remote import RayExecutor
from tests.exec.cluster import workers_running


def drive(mode: str, after: int, marker: str, argv: list[str]) -> dict[str, Any]:
    seen: dict[int, str] = {}
    state: dict[str, Any] = {"killed": [], "executor": None}
    original = RayExecutor.run

    def run(self: RayExecutor, cases: Any, on_result: Any = None, on_progress: Any = None,
            on_start: Any = None) -> Any:  # fmt: skip
        state["executor"] = self

        def hooked(index: int, result: Any) -> None:
            on_result(index, result)
            seen[index] = result.status
            if mode == "kill" and len(seen) >= after and not state["killed"]:
                for pid in workers_running(marker, "ray_task")[:1]:
                    os.kill(pid, signal.SIGKILL)
                    state["killed"].append(pid)
            elif mode == "interrupt" and len(seen) == after:
                os.kill(os.getpid(), signal.SIGINT)

        return original(self, cases, hooked, on_progress, on_start)

    RayExecutor.run = run  # type: ignore[method-assign]
    start = time.monotonic()
    code = main(argv)
    executor = state["executor"]
    return {"code": code, "retried": executor.retried if executor else None, "killed": state["killed"],
            "seen": seen, "seconds": time.monotonic() - start}  # fmt: skip


if __name__ == "__main__":
    mode, after, marker, sep, *rest = sys.argv[1:]
    assert sep == "--" and mode in ("kill", "interrupt")
    print(json.dumps(drive(mode, int(after), marker, rest)))
