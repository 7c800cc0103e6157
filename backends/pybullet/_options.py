"""The ``backend_options.pybullet`` block, and the solver size a scene gets (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option
from .._kit.stacks import refuse_column

#: PyBullet's own numSolverIterations, kept for every scene without a tall stack.
DEFAULT_ITERATIONS = 50
#: Solver sweeps per (stacked body)^2. Bullet's multibody solver is projected Gauss-Seidel (sequential
#: impulses); a load crosses one contact per sweep, and the error of a chain of H contacts falls by about
#: 1 - pi^2/H^2 per sweep, so the sweeps a column needs grow as H^2. Below the need, Bullet's unconverged
#: contacts act as soft springs: the column sways without damping (the whole column, speed growing with
#: height) until it buckles. Measured on ``box_pile.yaml`` (0.3 m boxes of 13.5 kg, dt 0.01, bounce 0.2,
#: mu 5000; settled = below 2 cm/s after 4 s): H 10 settles with 100-400 sweeps, H 20 with 1600 (800:
#: 0.008 m/s, 400: 0.015, 200: 0.13, 50-100: it falls), H 30 with 3200-3600 (1600: 0.026 m/s, 800: 0.069,
#: 400: it falls), so 4 H^2. Conformance 16 (a resting column, mu 1, 10 s, 1 mm/s) asks more: 5 boxes at
#: 4 H^2 = 100 sweeps break loose at 9 s (0.010 m/s), at 8 H^2 = 200 they stay below 1e-4 m/s, as do 10
#: at 800. 8 H^2 then, above :data:`DEFAULT_STACK`.
SWEEPS_PER_BODY_SQUARED = 8
#: The tallest column Bullet's default sweeps are kept for: conformance 12's resting column of 4 holds its
#: 1 mm and 1 mm/s for 10 s at 50 sweeps (measured, as before issue 17), and so does every scene of the
#: suite and the benchmarks' pile (columns of 4), whose traces and costs stay Bullet's own.
DEFAULT_STACK = 4
#: The tallest column the backend accepts. Measured on ``box_pile.yaml``: 40 boxes with 6400 sweeps still
#: sway at 0.05 m/s after 4 s (a box thrown at 2.95 m/s at t = 1.28 s by the landing), 50 boxes fall
#: whatever the sweeps (50-1600 at one step, 8-32 substeps of 50); a step costs ~5 ms per 1000 sweeps.
MAX_STACK = 30


@dataclass(frozen=True)
class PyBulletOptions(BackendOptions):
    solver_iterations: int | None = option(
        None, "numSolverIterations of the constraint solver (default: 50, or 8 H^2 for a world starting with a "
        "column of H > 4 bodies, see docs/backends/pybullet.md, Stacking)", minimum=1,
    )  # fmt: skip
    deterministic_overlapping_pairs: bool = option(
        True, "sort broadphase pairs for run-to-run determinism (default true)"
    )


def solver_iterations(options: PyBulletOptions, stack: int) -> int:
    """The solver sweeps for a world whose tallest column has ``stack`` bodies (the option wins)."""
    if options.solver_iterations is not None:
        return options.solver_iterations
    if stack <= DEFAULT_STACK:
        return DEFAULT_ITERATIONS
    return max(DEFAULT_ITERATIONS, SWEEPS_PER_BODY_SQUARED * stack * stack)


def check_stack(stack: int) -> None:
    """Refuse (when the backend picks the solver) a column taller than PyBullet holds (:data:`MAX_STACK`)."""
    refuse_column(
        "pybullet", stack, MAX_STACK, holds="PyBullet holds",
        why=f"its iterative contact solver needs about {SWEEPS_PER_BODY_SQUARED} x height^2 sweeps per step to "
        "keep a column standing, a column of 40 still swayed at 6400 and one of 50 fell at every setting tried "
        "(measured, docs/backends/pybullet.md, Stacking); use mujoco (up to 50) or dart, or set "
        "backend_options.pybullet.solver_iterations to run it anyway",
    )  # fmt: skip
