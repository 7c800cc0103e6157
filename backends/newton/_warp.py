"""Warp and Newton imported quietly, their kernel cache outside the repository, the device checked.

Warp prints a banner at ``init``, a CUDA-driver warning from native code on a machine without a GPU, and one
line per module it compiles or loads (``Module ... load on device``); none of that is about the run, so it is
kept out of the user's terminal (``log_level`` to warnings, the native warning's fd redirected during init).
The kernel cache (a first compile takes 30-80 s per solver, docs/backends/newton.md) goes to
``~/.cache/physics-scenarios/warp`` unless the environment sets ``WARP_CACHE_PATH``.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
from collections.abc import Iterator
from typing import Any

from ..errors import UnsupportedFeature

os.environ.setdefault("WARP_CACHE_PATH", os.path.join(os.path.expanduser("~"), ".cache", "physics-scenarios", "warp"))


@contextlib.contextmanager
def _silenced_fds() -> Iterator[None]:
    """stdout and stderr (the file descriptors: native code prints there) sent to /dev/null."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
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


def load() -> tuple[Any, Any]:
    """``(warp, newton)``, initialised once, quietly."""
    with _silenced_fds():
        import warp as wp

        wp.config.quiet = True
        wp.config.log_level = wp.LOG_WARNING  # no "Module ... load on device" line per compiled module
        wp.init()
        import newton
        import newton.solvers  # noqa: F401 - the solvers load lazily; import them here, quietly
    return wp, newton


def device(wp: Any, name: str) -> str:
    """The Warp device for the ``device`` option: ``cuda`` refused when Warp sees no CUDA device."""
    if name == "cuda" and not wp.is_cuda_available():
        raise UnsupportedFeature(
            "Backend `newton`: option `device: cuda`, but Warp sees no CUDA device on this machine (no NVIDIA "
            "driver or GPU); use `device: cpu`"
        )
    return "cuda:0" if name == "cuda" else "cpu"
