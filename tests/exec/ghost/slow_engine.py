"""A test-only engine module that takes 2 s to import and, as a pybind11 module's initialisation does, turns
any exception raised meanwhile (a KeyboardInterrupt from a signal handler) into ImportError: the way a
SIGTERM during `import mujoco` became "could not import its engine" (issue 15, item 11)."""

from __future__ import annotations

import time

from backends.fake import FakeBackend

try:
    time.sleep(2.0)
except BaseException as exc:  # noqa: BLE001 - what pybind11's PYBIND11_MODULE does with an init failure
    raise ImportError("initialization failed") from exc


class SlowImportBackend(FakeBackend):
    name = "slowimport"
