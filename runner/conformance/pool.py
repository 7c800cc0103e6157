"""Running the suite: each backend in its own process, several backends in parallel.

One worker process (:mod:`runner.conformance.worker`) per backend runs that backend's cases one after the
other and appends a line per case to a results file. When a worker dies (a segfault in an engine, a kill)
or a case runs past the timeout, the case it was running is marked ``crashed (signal N)``,
``crashed (exit N)`` or ``timed out``, and a fresh worker carries on with the cases after it: one broken
case never hides the others, and one broken backend never hides the other backends.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from backends.registry import engine_version
from runner.conformance.cases import Case

#: The source tree holding the ``runner`` and ``backends`` packages, put first on the worker's path.
ROOT = Path(__file__).resolve().parents[2]
POLL_SECONDS = 0.05
LOG_TAIL = 2000  # characters of a crashed worker's output kept for the message


@dataclass
class BackendRun:
    """Everything one backend's workers reported."""

    backend: str
    engine_version: str
    results: dict[str, dict[str, Any]] = field(default_factory=dict)  # case id -> worker result
    wall_seconds: float = 0.0
    workers: int = 0  # processes started (1 unless a case crashed or timed out)


def _signal_name(code: int) -> str:
    try:
        return signal.Signals(-code).name
    except ValueError:
        return f"signal {-code}"


def _failure(status: str, message: str) -> dict[str, Any]:
    return {"status": status, "message": message, "checks": [], "wall_seconds": 0.0}


def _read_lines(path: Path) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:  # a line cut off by a crash
            break
    return out


def _tail(path: Path) -> str:
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
    return text[-LOG_TAIL:].strip()


class _Worker:
    """One worker process over a list of cases, watched until it ends, crashes or hangs."""

    def __init__(self, backend: str, cases: Sequence[Case], folder: Path, number: int) -> None:
        self.job = folder / f"job{number}.json"
        self.out = folder / f"results{number}.jsonl"
        self.log = folder / f"log{number}.txt"
        self.job.write_text(json.dumps({"backend": backend, "cases": [c.job() for c in cases]}))
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
        env.setdefault("ALSOFT_DRIVERS", "null")
        with open(self.log, "wb") as log:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "runner.conformance.worker", str(self.job), str(self.out)],
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                cwd=ROOT,
            )

    def watch(self, timeout: float, stop: threading.Event | None) -> tuple[list[dict[str, Any]], str | None]:
        """Wait for the worker; returns its lines and, if it was stopped, why ("timed out", "interrupted")."""
        current, since = None, time.monotonic()
        while self.proc.poll() is None:
            if stop is not None and stop.is_set():
                self.stop()
                return _read_lines(self.out), "interrupted"
            lines = _read_lines(self.out)
            started = [x["case"] for x in lines if x.get("started")]
            if started and started[-1] != current:
                current, since = started[-1], time.monotonic()
            if time.monotonic() - since > timeout:
                self.proc.kill()
                self.proc.wait()
                return _read_lines(self.out), "timed out"
            time.sleep(POLL_SECONDS)
        return _read_lines(self.out), None

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


def run_backend(backend: str, cases: Sequence[Case], timeout: float, stop: threading.Event | None = None) -> BackendRun:
    """Run ``cases`` on ``backend`` in worker processes; every case gets a result."""
    run = BackendRun(backend, engine_version(backend))
    start = time.monotonic()
    remaining = list(cases)
    with tempfile.TemporaryDirectory(prefix=f"conformance-{backend}-") as tmp:
        while remaining and not (stop is not None and stop.is_set()):
            run.workers += 1
            worker = _Worker(backend, remaining, Path(tmp), run.workers)
            try:
                lines, stopped = worker.watch(timeout, stop)
            finally:
                worker.stop()
            for line in lines:
                if "result" in line:
                    run.results[line["case"]] = line["result"]
            done = [c for c in remaining if c.id in run.results]
            cut = next((c for c in remaining if c.id not in run.results), None)
            if cut is None:
                break
            code = worker.proc.returncode
            started = any(x.get("case") == cut.id and x.get("started") for x in lines)
            if stopped == "interrupted":
                break
            if stopped:
                status = f"timed out after {timeout:g} s"
            elif code is not None and code < 0:
                status = f"crashed ({_signal_name(code)})"
            else:
                status = f"crashed (exit {code})"
            run.results[cut.id] = _failure(status, _tail(worker.log))
            if not started and not done:
                # the worker died before its first case (an import error, a broken engine): no retry helps
                for c in remaining:
                    run.results.setdefault(c.id, _failure(status, _tail(worker.log)))
                break
            remaining = remaining[remaining.index(cut) + 1 :]
    run.wall_seconds = time.monotonic() - start
    return run


def run_suite(
    cases: Sequence[Case],
    backends: Sequence[str],
    jobs: int | None = None,
    timeout: float = 120.0,
    on_done: Callable[[BackendRun], None] | None = None,
) -> dict[str, BackendRun]:
    """Run every case on every backend, ``jobs`` backends at a time (default: one per core)."""
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(backends) or 1))
    stop = threading.Event()
    runs: dict[str, BackendRun] = {}

    def one(name: str) -> BackendRun:
        result = run_backend(name, cases, timeout, stop)
        if on_done is not None and not stop.is_set():
            on_done(result)
        return result

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {name: pool.submit(one, name) for name in backends}
        try:
            for name, future in futures.items():
                runs[name] = future.result()
        except BaseException:  # Ctrl-C, SIGTERM: the threads kill their workers, then this propagates
            stop.set()
            raise
    return runs
