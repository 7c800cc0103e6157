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
        0.05, "error reduction of contacts that bounce, while they approach slower than 1 cm/s (resting), and of "
        "all of them on MuJoCo's cone (mu > 20); impacts with Coulomb friction get ODE's bounce (default 0.05)",
        minimum=0.0, min_exclusive=True, maximum=1.0,
    )  # fmt: skip
    max_correcting_vel: float = option(
        0.1, "contact max correcting velocity, m/s: the speed at which erp may push a penetration out (ODE's "
        "dWorldSetContactMaxCorrectingVel; default 0.1: a body pushed out at it rises 0.5 mm)",
        minimum=0.0, min_exclusive=True,
    )  # fmt: skip
    engine_substeps: int = option(1, "MuJoCo steps per world substep (default 1)", minimum=1)
