"""Import pybullet without its C-level banner ("pybullet build time: ...") reaching our stdout or stderr.

PyBullet prints the banner with printf when its module loads; it would end up inside `--json` output and
CI logs. The banner goes to a discarded file descriptor, and C's stdio buffer is flushed before stdout is
restored, so nothing leaks later.
"""

from __future__ import annotations

import ctypes
import os
import sys
from types import ModuleType


def import_pybullet() -> ModuleType:
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    sys.stdout.flush()
    sys.stderr.flush()
    saved = {fd: os.dup(fd) for fd in (1, 2)}
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in saved:
            os.dup2(devnull, fd)
        import pybullet

        ctypes.CDLL(None).fflush(None)
    finally:
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)
    return pybullet
