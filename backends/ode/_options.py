"""The ``backend_options.ode`` block: keys, defaults (ODE's own) and bounds (imports no engine).

Defaults are the lab's: ``world.step`` (the accurate "big matrix" stepper), ERP 0.2 and CFM 1e-5, the
values ``dWorldCreate`` sets in this single-precision build. CFM 1e-10 (double-precision ODE's default)
makes this build's LCP fail ("LCP internal error, s <= 0") and the lab scene fly apart; 1e-9 failed
too and 1e-8 was the smallest value that stayed sound on it, so smaller values are refused.
"""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option
from .._kit.stacks import refuse_column

#: The tallest column dropped onto itself (bodies starting apart, docs/backends/ode.md, Stacking) the
#: backend accepts. Measured on ``box_pile.yaml`` (0.3 m boxes of 13.5 kg, dt 0.01, bounce 0.2, mu 5000;
#: settled = below 2 cm/s after 4 s): 20 boxes settle (0.0075 m/s); 25 and 30 do not. At the default CFM
#: 1e-5 every contact is a spring (kp = ERP/(h CFM)) that lets the landed column bend: at 30 each box
#: turns a little more than the one below (2.2 deg at the top), the top creeping 0.39 m in 6 s; quickstep
#: bends alike (7200 iterations: 0.46 m). A stiffer CFM gives ODE's single-precision LCP more failures
#: ("LCP internal error, s <= 0"), each a kick: at 30 boxes CFM 1e-6 and 2e-6 settle, 1.1e-6 throws a box
#: at 1.3 m/s and 5e-7 topples the column; quickstep 1000 and 4000 iterations settle, 1800 does not; two
#: substeps settle 30 and topple 25. No setting holds such columns reliably, so none is picked. A column
#: that starts resting is held by :data:`MAX_RESTING_STACK` instead.
MAX_LANDING_STACK = 20

#: The tallest column that starts resting (each body on the one below, docs/backends/ode.md, Stacking,
#: issue 27) the backend accepts when its contacts have friction. Each box face carries 4 contact points, so
#: its friction rows are redundant and dWorldStep's single-precision LCP meets a zero pivot ("LCP internal
#: error, s <= 0"): it zeroes the forces of every row left for that step and the column is kicked.
#: Measured: conformance 12's 4 boxes of 13.5 kg stand (1 mm bounds); conformance 16's 5, 10, 20, 30 do
#: not (kicks of 1.7-8.4 mm and up to 0.10 m/s); the issue's 20 boxes of 1 kg fall (2.2 m), and no
#: setting (CFM, ERP, friction pyramid, quickstep up to 1000 iterations, retaking the failed step) holds
#: them within 1 mm. Without friction (mu 0) there are no friction rows and the 20 boxes stand (0.07 mm).
MAX_RESTING_STACK = 4

#: Smallest accepted CFM (measured on the lab scene, see the module docstring).
MIN_CFM = 1e-8


@dataclass(frozen=True)
class OdeOptions(BackendOptions):
    stepper: str = option(
        "step", "step (dWorldStep, accurate, the default) or quickstep (dWorldQuickStep, iterative)",
        choices=("step", "quickstep"),
    )  # fmt: skip
    quickstep_iterations: int = option(20, "iterations of quickstep's SOR solver (ODE default 20)", minimum=1)
    erp: float = option(0.2, "global error reduction parameter, 0..1 (ODE default 0.2)", minimum=0.0, maximum=1.0)
    cfm: float = option(
        1e-5, f"global constraint force mixing, >= {MIN_CFM:g} (default 1e-5, single-precision ODE's)",
        minimum=MIN_CFM, maximum=1.0,
    )  # fmt: skip
    max_correcting_vel: float = option(
        0.1, "contact max correcting velocity, m/s (dWorldSetContactMaxCorrectingVel): the speed at which ERP may "
        "push a penetration out; bounces are not capped (default 0.1: a body pushed out at it rises 0.5 mm; ODE's "
        "own default inf turns a landing's penetration into launch speed)", minimum=0.0, min_exclusive=True,
    )  # fmt: skip
    impact_cfm: bool = option(
        True, "true (default): contacts approaching faster than 1 cm/s get a CFM of 1e-4 of their inverse mass "
        "times h, so restitution does not depend on mass (needs the callback collide); false: the world's CFM "
        "on every contact (ODE's own; autoCollide possible)",
    )  # fmt: skip
    space: str = option(
        "simple", "collision space: simple (the lab's, the default) or hash", choices=("simple", "hash")
    )
    collide: str = option(
        "auto", "auto (contacts made in C++ by OdeSpace.autoCollide, the default) or callback (the lab's Python "
        "near-callback with OdeUtil.collide; slower, same contacts)", choices=("auto", "callback"),
    )  # fmt: skip
    friction_pyramid: str = option(
        "slip", "slip (default): each contact's first friction direction along its slip, so a sliding body "
        "decelerates at mu*g in every direction (forces collide=callback when a surface has a finite mu > 0); "
        "axes: ODE's default directions, a pyramid fixed to the contact normal's basis (sqrt(2)*mu*g on the "
        "diagonal of a floor)", choices=("slip", "axes"),
    )  # fmt: skip
    contact_forces: bool = option(
        True, "true (default): joint feedback on the contact joints gives Contact.normal_force; false: NaN, and no "
        "per-contact Python work",
    )  # fmt: skip


def check_stack(landing: int) -> None:
    """Refuse a column dropped onto itself that is taller than ODE can settle (:data:`MAX_LANDING_STACK`)."""
    refuse_column(
        "ode", landing, MAX_LANDING_STACK, detail=" dropped onto each other", holds="ODE (single precision) settles",
        why="its soft contacts (CFM 1e-5) let a taller landed column bend and creep, and a stiffer CFM makes its "
        "LCP fail and kick the column (measured at 25 and 30 boxes, docs/backends/ode.md, Stacking); use mujoco "
        "(up to 50), pybullet (up to 30), dart, or start the column resting",
    )  # fmt: skip


def check_resting_stack(tallest: int, landing: int, friction: bool) -> None:
    """Refuse a column that starts resting, with friction, taller than :data:`MAX_RESTING_STACK`.

    ``tallest > landing`` means the tallest column has no dropped link (a dropped link makes it landing).
    """
    if friction and tallest > landing:
        refuse_column(
            "ode", tallest, MAX_RESTING_STACK, column="a resting column", detail=" with friction",
            holds="ODE (single precision) holds",
            why="the redundant friction rows of stacked faces make dWorldStep's LCP fail (LCP internal error, "
            "s <= 0) and kick the column (measured: 5 to 30 boxes of 13.5 kg move 1.7-8.4 mm, 20 boxes of 1 kg "
            "fall; docs/backends/ode.md, Stacking); use mujoco, pybullet or dart, or mu 0",
        )  # fmt: skip
