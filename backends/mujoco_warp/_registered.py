"""The registered ``mujoco_warp`` backend: the single-world adapter (``_backend``) that batches (``_batch``).

Kept apart so that the adapter and the batch, which builds its worlds from the adapter, do not import each other.
"""

from __future__ import annotations

from typing import ClassVar

from ..batch import WorldBatch
from ._backend import MujocoWarpBackend as SingleWorldBackend
from ._batch import MujocoWarpBatch


class MujocoWarpBackend(SingleWorldBackend):
    """MuJoCo's model stepped by MJWarp (docs/backends/mujoco_warp.md); many worlds at once (docs/batch.md)."""

    name: ClassVar[str] = SingleWorldBackend.name

    @classmethod
    def world_batch(cls) -> type[WorldBatch]:
        return MujocoWarpBatch
