"""A test-only backend that behaves like the fake backend and then kills or hangs its own process.

It exists to test engine isolation (``scenario compare``, ``scenario run --isolate``): an engine that
segfaults or hangs must not take the runner down, and its trace up to that point must be kept.
Options (``backend_options.crash``):

* ``after_steps`` (default 30): the fault happens right after this many steps;
* ``fault``: ``signal`` (default) sends ``signal`` to the process itself; ``hang`` sleeps forever (a
  SIGTERM still interrupts it); ``hang-ignoring-sigterm`` ignores SIGTERM first, so only SIGKILL ends it;
* ``signal`` (default ``SIGSEGV``): a name such as ``SIGKILL`` or a number;
* ``fault: allocate`` takes ``megabytes`` (default 1024) more memory, 64 MiB at a time with every page
  written (resident, as an engine building a huge world would), then hangs: the worker's memory ceiling
  (``SCENARIO_MEMORY_LIMIT``, docs/reliability.md) is what stops it.

A fault by signal disables core dumps first, so a test leaves no core file behind.
"""

from __future__ import annotations

import os
import signal
import time
from dataclasses import dataclass
from typing import Any, ClassVar

from ._kit import BackendOptions, option
from .fake import FakeBackend

FAULTS = ("signal", "hang", "hang-ignoring-sigterm", "allocate")
_CHUNK = 64 * 1024 * 1024


def signal_number(value: Any) -> int:
    """A signal given by name (``SIGSEGV``, ``segv``) or number; ValueError says what is expected."""
    expected = ValueError("a signal name such as SIGSEGV or a number")
    if isinstance(value, bool):
        raise expected
    if isinstance(value, int):
        number = value
    else:
        name = str(value).upper()
        member = signal.Signals.__members__.get(name if name.startswith("SIG") else f"SIG{name}")
        if member is None:
            raise expected
        number = int(member)
    if number not in {int(s) for s in signal.Signals}:
        raise expected
    return number


@dataclass(frozen=True)
class CrashOptions(BackendOptions):
    after_steps: int = option(30, "steps before the fault (default 30)", minimum=0)
    fault: str = option("signal", "signal (default) | hang | hang-ignoring-sigterm | allocate", choices=FAULTS)
    signal: int = option(int(signal.SIGSEGV), "the signal sent by fault `signal`, a name or a number (default SIGSEGV)",
                         convert=signal_number)  # fmt: skip
    megabytes: int = option(1024, "MiB held by fault `allocate` (default 1024)", minimum=1)


class CrashBackend(FakeBackend):
    name = "crash"
    Options: ClassVar[type[BackendOptions]] = CrashOptions
    options: CrashOptions

    def _settings(self) -> dict[str, Any]:
        o = self.options
        return {"after_steps": o.after_steps, "fault": o.fault, "signal": signal.Signals(o.signal).name,
                "megabytes": o.megabytes}  # fmt: skip

    def _step(self) -> None:
        super()._step()
        if self.steps + 1 >= self.options.after_steps:
            self._fault()

    def _fault(self) -> None:
        if self.options.fault == "signal":
            try:
                import resource

                resource.setrlimit(resource.RLIMIT_CORE, (0, resource.getrlimit(resource.RLIMIT_CORE)[1]))
            except (ImportError, ValueError, OSError):  # pragma: no cover - not on every platform
                pass
            os.kill(os.getpid(), self.options.signal)
            time.sleep(5.0)  # a signal that does not end the process (SIGCHLD...) falls through to a hang
        if self.options.fault == "allocate":
            held = [bytearray(b"\x01") * min(_CHUNK, self.options.megabytes * 1024 * 1024 - i * _CHUNK)
                    for i in range(-(-self.options.megabytes * 1024 * 1024 // _CHUNK))]  # fmt: skip
            while held:  # held until the process ends
                time.sleep(3600.0)
        if self.options.fault == "hang-ignoring-sigterm":
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
        while True:
            time.sleep(3600.0)
