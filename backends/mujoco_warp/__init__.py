"""The MuJoCo Warp backend: the MuJoCo backend's model handed to MJWarp (``mujoco_warp``) and stepped there.

The adapter (and with it Warp, MJWarp and MuJoCo) is imported on first use of ``MujocoWarpBackend``, so that
the engine-free parts (``_options``) can be read without the engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._registered import MujocoWarpBackend

__all__ = ["MujocoWarpBackend"]


def __getattr__(name: str) -> Any:
    if name == "MujocoWarpBackend":  # the single-world adapter (_backend) with its batch (_batch)
        from ._registered import MujocoWarpBackend

        return MujocoWarpBackend
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
