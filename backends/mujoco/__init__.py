"""The MuJoCo backend: a CompiledWorld built through ``mujoco.MjSpec``, stepped with ODE semantics.

The adapter (and with it the engine) is imported on first use of ``MujocoBackend``, so that the engine-free
parts (``_options``) can be read without the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._backend import MujocoBackend

__all__ = ["MujocoBackend"]


def __getattr__(name: str) -> Any:
    if name == "MujocoBackend":
        from ._backend import MujocoBackend

        return MujocoBackend
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
