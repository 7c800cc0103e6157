"""The child side of the protocol: a worker process that runs the jobs its parent sends, one at a time.

:func:`serve` is the worker's main function (started by :mod:`runner.exec.pool`). It

* leaves the parent's process group, so that a Ctrl-C at the terminal reaches the parent only (the
  parent decides what each worker is told), and asks the kernel for SIGTERM when its parent dies
  (Linux), so an orphaned worker finishes its trace and ends;
* sends what the process prints (engines print, and abort messages come on stderr) to a log file the
  parent reads: the tail of it names the cause of a crash;
* installs the interruption handlers of :mod:`runner.interrupts` (a signal is raised at the next safe
  point of a run; a second one ends the process at once; :data:`BACKSTOP` seconds after the first, an
  alarm does);
* then loops: receive ``(job id, function, args)``, reply ``("started", id)``, optionally
  ``("progress", id, k, n)``, and ``("done", id, payload)`` where ``payload`` is the function's return
  value, a JSON-able dictionary. A job reports its own errors in its payload (see
  :func:`runner.exec.cases.run_case`); anything that escapes it is sent as ``{"status": "error", ...}``.

The worker ends when its parent sends ``None``, closes the pipe, or is gone.
"""

from __future__ import annotations

import contextlib
import ctypes
import faulthandler
import os
import signal
import sys
import time
from collections.abc import Callable
from multiprocessing.connection import Connection
from typing import Any

from runner import interrupts

__all__ = ["Report", "serve"]

Report = Callable[[int, int], None]  # (steps done, steps in all)
_PR_SET_PDEATHSIG = 1
_PROGRESS_EVERY = 0.2  # seconds between progress messages
#: seconds after an interruption at which a worker ends whatever it is doing (the parent kills it sooner,
#: after its grace period; this bounds an orphan whose engine call never returns)
BACKSTOP = 20


def _detach(log_path: str | None) -> None:
    faulthandler.disable()  # an inherited handler (pytest's) would print a crash to the parent's stderr
    with contextlib.suppress(OSError):
        os.setpgid(0, 0)
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    if log_path is not None:
        try:
            fd = os.open(log_path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
        except OSError:  # the parent is already gone and took its folder with it: say nothing
            fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        os.close(fd)


class _Reporter:
    """The job's progress callback: ``("progress", id, k, n)`` at most every :data:`_PROGRESS_EVERY` s."""

    def __init__(self, conn: Connection, job_id: int) -> None:
        self.conn, self.job_id, self.last = conn, job_id, 0.0

    def __call__(self, k: int, n: int) -> None:
        now = time.monotonic()
        if now - self.last >= _PROGRESS_EVERY or k == n:
            self.last = now
            self.conn.send(("progress", self.job_id, k, n))


def serve(conn: Connection, log_path: str | None) -> None:
    """The worker's main function (see the module docstring)."""
    _detach(log_path)
    interrupts.install(always=True, backstop=BACKSTOP)
    from runner.exec.transport import encode_error

    parent = os.getppid()
    while True:
        try:
            while not conn.poll(1.0):  # a forked worker holds its parent's end too: EOF never comes
                if os.getppid() != parent:  # orphaned between jobs: nobody will send another
                    return
            message = conn.recv()
        except (EOFError, OSError, KeyboardInterrupt):
            return
        if message is None:
            return
        job_id, function, args = message
        interrupts.forget()
        report = _Reporter(conn, job_id)

        try:
            conn.send(("started", job_id))
            payload: dict[str, Any] = function(*args, report)
        except KeyboardInterrupt as exc:  # outside the job's own guard: the parent is stopping us
            payload = {"status": "interrupted", "signal": interrupts.signal_of(exc)}
        except Exception as exc:  # noqa: BLE001 - a bug outside the job's guard still reaches the parent
            payload = {"status": "error", "error": encode_error(exc)}
        sys.stdout.flush()
        sys.stderr.flush()
        try:
            conn.send(("done", job_id, payload))
        except (OSError, KeyboardInterrupt):
            return
