"""The ``backend_options.mujoco_warp`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import option
from ..mujoco._options import MujocoOptions


@dataclass(frozen=True)
class MujocoWarpOptions(MujocoOptions):
    device: str = option(
        "cpu", "Warp device the worlds run on: `cpu` (deterministic, tested in CI) or `cuda` / `cuda:N` (a GPU; "
        "MJWarp's GPU atomics make runs differ in the last bits unless its determinism flags are set)",
        choices=("cpu", "cuda", "cuda:0", "cuda:1", "cuda:2", "cuda:3"),
    )  # fmt: skip
    contacts_per_body: int = option(
        8, "contact buffer per world: this many contacts per body, plus 8 (MJWarp's default of 48 per world "
        "silently drops contacts of a pile; a step that fills the buffer is an engine failure)", minimum=1,
    )  # fmt: skip
