"""Warp and Newton imported quietly, their kernel cache outside the repository, the device checked.

Warp prints a banner at ``init``, a CUDA-driver warning from native code on a machine without a GPU, and one
line per module it compiles or loads (``Module ... load on device``); none of that is about the run, so it is
kept out of the user's terminal (``log_level`` to warnings, the native warning's fd redirected during init).
The kernel cache (a first compile takes 30-80 s per solver, docs/backends/newton.md) goes to
``~/.cache/physics-scenarios/warp`` unless the environment sets ``WARP_CACHE_PATH``.
"""

from __future__ import annotations

from typing import Any

from .._kit.quiet import keep_warp_cache_outside, silenced_output
from ..errors import UnsupportedFeature

keep_warp_cache_outside()


def load() -> tuple[Any, Any]:
    """``(warp, newton)``, initialised once, quietly."""
    with silenced_output():
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
