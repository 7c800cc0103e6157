"""The ``backend_options.pybullet`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option


@dataclass(frozen=True)
class PyBulletOptions(BackendOptions):
    solver_iterations: int = option(50, "numSolverIterations of the constraint solver (default 50)", minimum=1)
    deterministic_overlapping_pairs: bool = option(
        True, "sort broadphase pairs for run-to-run determinism (default true)"
    )
