"""SIGINT and SIGTERM: at the next safe point of a run, never inside the trace writer or an engine's import.

The process that runs cases (a worker of :mod:`runner.exec`) installs the handlers (:func:`install`) and
runs each case inside :class:`deferred`: a signal that arrives there is only remembered, and raised by
the next :func:`check`: after each recorded step (the step loop), after the engine is imported and
after the world is built. So a trace interrupted by Ctrl-C or SIGTERM always ends with a whole step
and is finished cleanly (status interrupted), and a signal during an engine's import is an
interruption (exit 130/143), never a broken import.

A second signal while the first is still pending (an engine call that does not return) ends the process
at once by the signal's default action: the trace stays a ``.partial`` file, readable up to its last
complete chunk, and the parent reports the interruption. Outside :class:`deferred` (the CLI's own
process) a signal is raised at once, as Python's default would.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Callable
from types import FrameType, TracebackType

__all__ = ["Terminated", "behind", "check", "deferred", "forget", "install", "kind_of", "pending", "signal_of"]


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that traces are finished like on Ctrl-C."""


_pending: type[KeyboardInterrupt] | None = None
_depth = 0
_backstop = 0  # seconds a deferred signal may stay pending before SIGALRM ends the process (0: no limit)


def check() -> None:
    """Raise the signal that arrived since the last check, if any."""
    global _pending
    if _pending is not None:
        kind, _pending = _pending, None
        raise kind()


def kind_of(signum: int) -> type[KeyboardInterrupt]:
    return Terminated if signum == signal.SIGTERM else KeyboardInterrupt


def signal_of(exc: BaseException) -> int:
    """The signal an interruption stands for: SIGTERM for :class:`Terminated`, else SIGINT."""
    return int(signal.SIGTERM if isinstance(exc, Terminated) else signal.SIGINT)


def behind(exc: BaseException) -> KeyboardInterrupt | None:
    """The SIGINT/SIGTERM behind ``exc``: itself, or one that Python or a library wrapped while it was raised
    (a class being built wraps it in RuntimeError, a pybind11 module's initialisation in ImportError)."""
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if isinstance(current, KeyboardInterrupt):
            return current
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return None


class deferred:  # noqa: N801 - used as a statement: `with deferred():`
    """Signals that arrive inside are held until :func:`check` (or the end of the block, unless
    ``check_at_exit`` is false: then a signal still pending is left for whoever checks next)."""

    def __init__(self, check_at_exit: bool = True) -> None:
        self._check = check_at_exit

    def __enter__(self) -> None:
        global _depth
        _depth += 1

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        global _depth
        _depth -= 1
        if exc_type is None and _depth == 0 and self._check:
            check()


def pending() -> bool:
    """A signal arrived and has not been raised yet."""
    return _pending is not None


def forget() -> None:
    """Drop a pending signal (a worker starting its next job)."""
    global _pending
    _pending = None


def _handler(signum: int, frame: FrameType | None) -> None:
    global _pending
    if _depth == 0:
        _pending = None
        raise kind_of(signum)()
    if _pending is not None:  # the second one: end now, by the signal's own default action
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
        return
    _pending = kind_of(signum)
    if _backstop:
        signal.alarm(_backstop)  # an engine call that never returns cannot keep this process alive


def install(always: bool = False, backstop: int = 0) -> Callable[[], None]:
    """Install the handlers (SIGINT only if it is not ignored, unless ``always``: a worker obeys its parent
    whatever it inherited); return a function that restores the old ones. ``backstop``: seconds after a
    deferred signal at which SIGALRM (its default action) ends the process if nothing else did: an
    orphaned worker told by the kernel that its parent died never outlives it by more than that."""
    global _pending, _backstop
    _pending = None
    _backstop = backstop
    previous = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        if always or signal.getsignal(sig) is not signal.SIG_IGN:
            previous[sig] = signal.signal(sig, _handler)

    def restore() -> None:
        for sig, handler in previous.items():
            signal.signal(sig, handler)

    return restore
