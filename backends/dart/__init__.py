"""DART (dartpy) backend with ODE semantics; see docs/backends/dart.md for the mapping and deviations."""

from __future__ import annotations

from ._backend import DartBackend

__all__ = ["DartBackend"]
