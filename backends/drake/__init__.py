"""The Drake (pydrake MultibodyPlant + SceneGraph) backend with ODE semantics; docs/backends/drake.md.

The adapter (and with it the engine) is imported on first use of ``DrakeBackend``, so that the engine-free
parts (``_options``) can be read without the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._backend import DrakeBackend

__all__ = ["DrakeBackend"]


def __getattr__(name: str) -> Any:
    if name == "DrakeBackend":
        from ._backend import DrakeBackend

        return DrakeBackend
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
