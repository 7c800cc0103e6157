"""SIGINT and SIGTERM during a run take effect at the next step boundary, never inside the trace writer.

`scenario` installs the handlers (:func:`install`). While a run is recording (:class:`deferred`, entered
by :func:`runner.sim.run.run_loaded`), a signal is only remembered; the step loop calls :func:`check` after
each recorded step and raises it there, so a trace interrupted by Ctrl-C or SIGTERM always ends with a
whole step and is finished cleanly (status interrupted). Outside a run, or on a second signal (an engine
call that does not return), the signal is raised at once, as Python's default would.
"""

from __future__ import annotations

import signal
from collections.abc import Callable
from types import FrameType, TracebackType


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that traces are finished like on Ctrl-C."""


_pending: type[KeyboardInterrupt] | None = None
_depth = 0


def check() -> None:
    """Raise the signal that arrived since the last check, if any."""
    global _pending
    if _pending is not None:
        kind, _pending = _pending, None
        raise kind()


class deferred:  # noqa: N801 - used as a statement: `with deferred():`
    """Signals that arrive inside are held until :func:`check` (or the end of the block)."""

    def __enter__(self) -> None:
        global _depth
        _depth += 1

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        global _depth
        _depth -= 1
        if exc_type is None and _depth == 0:
            check()


def _handler(signum: int, frame: FrameType | None) -> None:
    global _pending
    kind = Terminated if signum == signal.SIGTERM else KeyboardInterrupt
    if _depth == 0 or _pending is not None:
        _pending = None
        raise kind()
    _pending = kind


def install() -> Callable[[], None]:
    """Install the handlers (SIGINT only if it is not ignored); return a function that restores the old ones."""
    global _pending
    _pending = None
    previous = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            previous[sig] = signal.signal(sig, _handler)

    def restore() -> None:
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    return restore
