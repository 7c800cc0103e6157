"""Native libraries kept out of the user's terminal, and Warp's kernel cache kept out of the repository.

Warp (under MuJoCo Warp and Newton) prints a banner at ``init``, a CUDA-driver warning from native code on a
machine without a GPU (straight to file descriptor 2, past ``sys.stderr``), and a line per module it compiles or
loads: none of it is about the run. Its kernel cache (a first compile takes 20-100 s per kind of scene,
docs/backends/mujoco_warp.md and newton.md) goes to ``~/.cache/physics-scenarios/warp`` unless the environment
sets ``WARP_CACHE_PATH``. Nothing here imports an engine.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
from collections.abc import Iterator

#: Warp's kernel cache when the environment names none
WARP_CACHE = os.path.join(os.path.expanduser("~"), ".cache", "physics-scenarios", "warp")


def keep_warp_cache_outside() -> None:
    """``WARP_CACHE_PATH`` set to :data:`WARP_CACHE` unless the environment sets it (before Warp's import)."""
    os.environ.setdefault("WARP_CACHE_PATH", WARP_CACHE)


@contextlib.contextmanager
def silenced_output() -> Iterator[None]:
    """stdout and stderr sent to /dev/null meanwhile, the file descriptors too (native code writes there)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)
