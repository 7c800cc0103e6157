"""The one mapping from how something ended to an exit code and a first message line, on every path.

:func:`classify` is used by the CLI for an exception raised in its own process and by
:class:`runner.exec.cases.CaseResult` for an exception a child sent back (rebuilt with its class by
:mod:`runner.exec.transport`), so the same scenario gives the same exit code and the same first line
serially, with ``-j N``, ``--isolate``, ``--trace-process``, on Ray and as a row of ``compare``:

=====================================================  ====  ==========================================
how it ended                                           code  first line
=====================================================  ====  ==========================================
every assertion passed                                 0     passed
an assertion failed                                    1     failed: ...
bad input: scenario, option, path, unknown backend,    2     error: ...
unsupported feature, an output another run is using
the engine: missing, failed, blew up, crashed (signal  3     engine failure: ... / crashed (signal N)
N), timed out, over its budget, over its memory              / timed out ... / over memory: ...
ceiling (SCENARIO_MEMORY_LIMIT)
a bug in this tool                                     70    internal error, please report: ...
an output could not be written (disk full, I/O)        74    output error: ...
SIGINT / SIGTERM                                       130   interrupted / terminated
                                                       143
=====================================================  ====  ==========================================

A command that ran several cases exits with the most severe of their codes, in the order of
:data:`SEVERITY` (an interruption first, then a bug, an output error, bad input, the engine, a failed
assertion).
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from dataclasses import dataclass

from runner.errors import (
    BackendError,
    ExitCode,
    InternalError,
    OutputError,
    PhysicsScenariosError,
    ScenarioError,
    TraceError,
    UnknownBackend,
    UnsupportedFeature,
)
from runner.interrupts import Terminated, behind
from runner.trace.output import RESOURCE_ERRNOS

__all__ = ["RESOURCE_ERRNOS", "SEVERITY", "Exit", "classify", "first_line", "most_severe"]

#: the command's exit code is the first of these that any of its cases ended with
SEVERITY = (
    ExitCode.TERMINATED,
    ExitCode.INTERRUPTED,
    ExitCode.INTERNAL_ERROR,
    ExitCode.OUTPUT_ERROR,
    ExitCode.BAD_INPUT,
    ExitCode.ENGINE_FAILURE,
    ExitCode.ASSERTION_FAILED,
    ExitCode.OK,
)

LABELS = {
    ExitCode.BAD_INPUT: "error",
    ExitCode.ENGINE_FAILURE: "engine failure",
    ExitCode.INTERNAL_ERROR: "internal error, please report",
    ExitCode.OUTPUT_ERROR: "output error",
    ExitCode.INTERRUPTED: "interrupted",
    ExitCode.TERMINATED: "terminated",
}


@dataclass(frozen=True)
class Exit:
    """The exit code and first line a command gives for an outcome."""

    code: ExitCode
    label: str  # what the first line starts with: "error", "engine failure", ...
    message: str  # the exception's message (may span lines)

    @property
    def headline(self) -> str:
        """The first message line: ``<label>: <first line of the message>``."""
        text = first_line(self.message)
        return f"{self.label}: {text}" if text else self.label


def first_line(text: str) -> str:
    return text.strip().splitlines()[0] if text.strip() else ""


def _code(exc: BaseException) -> ExitCode:
    if isinstance(exc, Terminated):
        return ExitCode.TERMINATED
    if isinstance(exc, KeyboardInterrupt):
        return ExitCode.INTERRUPTED
    if isinstance(exc, OutputError):
        return ExitCode.OUTPUT_ERROR
    if isinstance(exc, OSError):
        return ExitCode.OUTPUT_ERROR if exc.errno in RESOURCE_ERRNOS else ExitCode.BAD_INPUT
    if isinstance(exc, ScenarioError | UnknownBackend | UnsupportedFeature | TraceError) or _trace_read_error(exc):
        return ExitCode.BAD_INPUT
    if isinstance(exc, InternalError):
        return ExitCode.INTERNAL_ERROR
    if isinstance(exc, BackendError):
        return ExitCode.ENGINE_FAILURE
    if isinstance(exc, PhysicsScenariosError):  # a new branch of the tree nobody mapped: a bug
        return ExitCode.INTERNAL_ERROR
    return ExitCode.INTERNAL_ERROR


def _trace_read_error(exc: BaseException) -> bool:
    """A trace that cannot be read (reports.trace_reader.TraceReadError). The reader (protobuf, mcap) is not
    imported for this: a process that never imported it cannot have raised its error (a `scenario run` starts
    faster without it)."""
    reader = sys.modules.get("reports.trace_reader")
    return reader is not None and isinstance(exc, reader.TraceReadError)


def classify(exc: BaseException) -> Exit:
    """The exit code, label and message for ``exc``, wherever it was raised."""
    exc = behind(exc) or exc
    code = _code(exc)
    if isinstance(exc, OSError) and not isinstance(exc, PhysicsScenariosError):
        where = f"{exc.filename}: " if exc.filename else ""
        message = f"{where}{exc.strerror or exc}"
    elif isinstance(exc, KeyboardInterrupt):
        message = "traces written so far are finished and marked interrupted"
    elif code is ExitCode.INTERNAL_ERROR and not isinstance(exc, InternalError):
        message = f"{type(exc).__name__}: {exc}"
    elif _trace_read_error(exc):
        message = f"cannot read the trace: {exc}"
    else:
        message = str(exc)
    return Exit(code, LABELS.get(code, "error"), message)


def most_severe(codes: Iterable[int]) -> ExitCode:
    """The exit code of a command whose cases ended with ``codes`` (see :data:`SEVERITY`)."""
    seen = {int(c) for c in codes}
    return next((c for c in SEVERITY if int(c) in seen), ExitCode.OK)
