"""DART (dartpy) backend with ODE semantics; see docs/backends/dart.md for the mapping and deviations.

The adapter (and with it the engine) is imported on first use of ``DartBackend``, so that the engine-free
parts (``_options``) can be read without the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._backend import DartBackend

__all__ = ["DartBackend"]


def __getattr__(name: str) -> Any:
    if name == "DartBackend":
        from ._backend import DartBackend

        return DartBackend
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
