"""The ``backend_options.mujoco`` block (imports no engine)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._kit import BackendOptions, option
from .._kit.stacks import refuse_column

#: Longest engine step times the height of the tallest column (s x bodies). MuJoCo's contact here is a
#: spring of K = erp/h^2 per unit mass (the direct solref of docs/backends/mujoco.md), so the moment a
#: tilted column's contacts return grows as 1/h^2, while the overturning moment of a column of H bodies
#: grows as H^2 (H weights, lever H/2 heights): keeping h*H fixed keeps the ratio. Measured on
#: ``box_pile.yaml`` (0.3 m boxes, bounce 0.2 so resting contacts use bounce_erp 0.05, dt 0.01): one step
#: of 10 ms holds 20 boxes (h*H 0.2), 30 boxes lean 3 cm and fail at one step (0.3) and stand at two
#: (0.15); 50 stand at four (0.125). 0.15 keeps every measured height standing.
STEP_TIMES_HEIGHT = 0.15
#: The tallest column the backend accepts. Measured: 100 boxes never settle, at 4, 7, 10 or 20 engine
#: steps per 10 ms (the top sways at 0.16-1.2 m/s and the column leans 0.5-1.9 m; at 20 steps the landing
#: throws the top box at 24 m/s); at one step MuJoCo throws it at 29.5 m/s (issue 17).
MAX_STACK = 50


@dataclass(frozen=True)
class MujocoOptions(BackendOptions):
    """The MuJoCo adapter's options (`backend_options: {mujoco: {...}}`), each with its default and bounds."""

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
    engine_substeps: int | None = option(
        None, "MuJoCo steps per world substep (default: 1, or enough that step x height of the tallest starting "
        "column <= 0.15 s, see docs/backends/mujoco.md, Stacking)", minimum=1,
    )  # fmt: skip


def engine_substeps(options: MujocoOptions, step: float, stack: int) -> int:
    """MuJoCo steps per world substep of ``step`` seconds for a tallest column of ``stack`` (the option wins)."""
    if options.engine_substeps is not None:
        return options.engine_substeps
    return max(1, math.ceil(step * stack / STEP_TIMES_HEIGHT - 1e-9))


def check_stack(stack: int) -> None:
    """Refuse (when the backend picks the solver) a column taller than MuJoCo can hold standing (:data:`MAX_STACK`)."""
    refuse_column(
        "mujoco", stack, MAX_STACK, holds="MuJoCo holds",
        why="its soft contacts let a taller column lean and sway however short the step (100 boxes measured at 1 "
        "to 20 engine steps per 10 ms, docs/backends/mujoco.md, Stacking); use dart, or set "
        "backend_options.mujoco.engine_substeps to run it anyway",
    )  # fmt: skip
