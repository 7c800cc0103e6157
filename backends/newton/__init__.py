"""The NVIDIA Newton backend (on Warp) with ODE semantics; docs/backends/newton.md.

The adapter (and with it Warp and Newton) is imported on first use of ``NewtonBackend``, so that the
engine-free parts (``_options``, ``_surfaces``) can be read without the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._backend import NewtonBackend

__all__ = ["NewtonBackend"]


def __getattr__(name: str) -> Any:
    if name == "NewtonBackend":
        from ._backend import NewtonBackend

        return NewtonBackend
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
