"""The ``backend_options.mujoco`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option


@dataclass(frozen=True)
class MujocoOptions(BackendOptions):
    erp: float = option(
        0.2, "ODE-style error reduction per engine step of contacts and joint stops (default 0.2)",
        minimum=0.0, min_exclusive=True, maximum=1.0,
    )  # fmt: skip
    bounce_erp: float = option(
        0.05, "error reduction of contacts that bounce; adds up to this to the rebound (default 0.05)",
        minimum=0.0, min_exclusive=True, maximum=1.0,
    )  # fmt: skip
    engine_substeps: int = option(1, "MuJoCo steps per world substep (default 1)", minimum=1)
