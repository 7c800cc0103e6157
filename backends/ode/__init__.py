"""The ODE reference backend: the Open Dynamics Engine through panda3d.ode (no ShowBase, no window).

The adapter (and with it the engine) is imported on first use of ``OdeBackend``, so that the engine-free
parts (``_options``) can be read without the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._backend import OdeBackend

__all__ = ["OdeBackend"]


def __getattr__(name: str) -> Any:
    if name == "OdeBackend":
        from ._backend import OdeBackend

        return OdeBackend
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
