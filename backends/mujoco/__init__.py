"""The MuJoCo backend: a CompiledWorld built through ``mujoco.MjSpec`` and stepped with ODE semantics.

The mapping and its measured deviations from ODE are in docs/backends/mujoco.md.
"""

from __future__ import annotations

from ._backend import MujocoBackend

__all__ = ["MujocoBackend"]
