"""A test-only backend that behaves like the fake backend and then kills or hangs its own process.

It exists to test engine isolation (``scenario compare``, ``scenario run --isolate``): an engine that
segfaults or hangs must not take the runner down, and its trace up to that point must be kept.
Options (``backend_options.crash``):

* ``after_steps`` (default 30): the fault happens right after this many steps;
* ``fault``: ``signal`` (default) sends ``signal`` to the process itself; ``hang`` sleeps forever (a
  SIGTERM still interrupts it); ``hang-ignoring-sigterm`` ignores SIGTERM first, so only SIGKILL ends it;
* ``signal`` (default ``SIGSEGV``): a name such as ``SIGKILL`` or a number.

A fault by signal disables core dumps first, so a test leaves no core file behind.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Mapping
from typing import Any, ClassVar

from .errors import UnsupportedFeature
from .fake import FakeBackend
from .types import CompiledWorld

FAULTS = ("signal", "hang", "hang-ignoring-sigterm")


def _signal_number(value: Any) -> int:
    if isinstance(value, bool):
        raise UnsupportedFeature(f"Invalid `backend_options.crash.signal`. Expected a signal. Received: {value!r}")
    if isinstance(value, int):
        number = value
    else:
        name = str(value).upper()
        name = name if name.startswith("SIG") else f"SIG{name}"
        member = signal.Signals.__members__.get(name)
        if member is None:
            raise UnsupportedFeature(
                f"Invalid `backend_options.crash.signal`. Expected a signal name such as SIGSEGV or a number. "
                f"Received: {value!r}"
            )
        number = int(member)
    if number not in {int(s) for s in signal.Signals}:
        raise UnsupportedFeature(f"Invalid `backend_options.crash.signal`. Expected a signal. Received: {value!r}")
    return number


class CrashBackend(FakeBackend):
    name = "crash"
    option_keys: ClassVar[Mapping[str, str]] = {
        "after_steps": "steps before the fault (default 30)",
        "fault": "signal (default) | hang | hang-ignoring-sigterm",
        "signal": "the signal sent by fault `signal`, a name or a number (default SIGSEGV)",
    }

    def __init__(self, world: CompiledWorld) -> None:
        super().__init__(world)
        options = world.options_for(self.name)
        after = options.get("after_steps", 30)
        if isinstance(after, bool) or not isinstance(after, int) or after < 0:
            raise UnsupportedFeature(
                f"Invalid `backend_options.crash.after_steps`. Expected an integer >= 0. Received: {after!r}"
            )
        fault = options.get("fault", "signal")
        if fault not in FAULTS:
            raise UnsupportedFeature(
                f"Invalid `backend_options.crash.fault`. Expected one of {', '.join(FAULTS)}. Received: {fault!r}"
            )
        self.after_steps = after
        self.fault = str(fault)
        self.signal = _signal_number(options.get("signal", "SIGSEGV"))
        self.steps_done = 0

    def settings(self) -> dict[str, Any]:
        return {"after_steps": self.after_steps, "fault": self.fault, "signal": signal.Signals(self.signal).name}

    def step(self) -> None:
        super().step()
        self.steps_done += 1
        if self.steps_done >= self.after_steps:
            self._fault()

    def _fault(self) -> None:
        if self.fault == "signal":
            try:
                import resource

                resource.setrlimit(resource.RLIMIT_CORE, (0, resource.getrlimit(resource.RLIMIT_CORE)[1]))
            except (ImportError, ValueError, OSError):  # pragma: no cover - not on every platform
                pass
            os.kill(os.getpid(), self.signal)
            time.sleep(5.0)  # a signal that does not end the process (SIGCHLD...) falls through to a hang
        if self.fault == "hang-ignoring-sigterm":
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
        while True:
            time.sleep(3600.0)
