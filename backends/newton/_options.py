"""The ``backend_options.newton`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option
from .._kit.stacks import refuse_column

#: The Newton solvers the adapter offers (docs/backends/newton.md, "Solver"). SolverMuJoCo is not offered: it
#: needs mujoco 3.17, which conflicts with the mujoco 4 of the project's MuJoCo backends.
SOLVERS = ("xpbd", "featherstone")
DEVICES = ("cpu", "cuda")

#: The tallest column that starts resting (each body on the one below) the backend accepts. Measured with XPBD
#: (conformance 16, 0.3 m boxes of 13.5 kg, mu 1, dt 0.01, 16 iterations): 5 boxes stand, the top 12.1 mm low
#: and the column still moving at 2.2 mm/s; 10 sink 73 mm and move at 0.23 m/s; 20 and 30 gain energy until the
#: watchdog stops the run (the top box 10.8 J and 16.9 J in one step). A column dropped onto itself is not
#: limited: the contract suite's busy world (7 boxes falling onto each other) runs, bit for bit the same twice.
MAX_RESTING_STACK = 5


def check_stack(tallest: int, landing: int) -> None:
    """Refuse a resting column taller than XPBD is measured to hold standing (:data:`MAX_RESTING_STACK`);
    ``tallest > landing``: the tallest column has no dropped link."""
    if tallest > landing:
        refuse_column(
            "newton", tallest, MAX_RESTING_STACK, column="a resting column", holds="Newton's XPBD holds",
            why="its contacts are relaxed position corrections, and a column of 10 boxes of 0.3 m sinks 73 mm, "
            "20 gain energy until the watchdog stops the run (docs/backends/newton.md, Conformance); use "
            "mujoco, pybullet or dart",
        )  # fmt: skip


@dataclass(frozen=True)
class NewtonOptions(BackendOptions):
    solver: str = option(
        "xpbd", "xpbd (default): Newton's position-based solver in maximal coordinates, hard contacts with "
        "restitution and per-contact forces; featherstone: reduced coordinates with penalty contacts (no "
        "restitution coefficient: a world with bounce is refused; contact forces estimated from the penalty "
        "law), docs/backends/newton.md", choices=SOLVERS,
    )  # fmt: skip
    device: str = option(
        "cpu", "the Warp device: cpu (default) or cuda (refused when Warp sees no CUDA device)", choices=DEVICES,
    )  # fmt: skip
    iterations: int = option(
        16, "XPBD constraint iterations per engine step (Newton's default is 2: a hinge stop at dt 0.01 then "
        "overshoots to 1.1 rad instead of 0.52; at 8 the lab box rests 3.2 mm deep at dt 0.04, at 16 0.45 mm; "
        "docs/backends/newton.md)", minimum=1,
    )  # fmt: skip
    contact_stiffness: float = option(
        1e4, "featherstone only: the penalty contact stiffness ke (N/m per contact point; integrated explicitly, "
        "so bounded by dt: 1e6 blows the resting lab box up at dt 0.01)", minimum=0.0, min_exclusive=True,
    )  # fmt: skip
    limit_stiffness: float = option(
        1e3, "featherstone only: the joint stops' penalty stiffness limit_ke (N/m or N m/rad); XPBD's stops are "
        "hard constraints", minimum=0.0, min_exclusive=True,
    )  # fmt: skip
    limit_damping: float = option(
        10.0, "featherstone only: the joint stops' penalty damping limit_kd (N s/m or N m s/rad)", minimum=0.0,
    )  # fmt: skip
