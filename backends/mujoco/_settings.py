"""The MuJoCo adapter's engine settings as a trace records them (``Backend.settings``): the model file's own
options, or the options the adapter sets for ODE's semantics (docs/backends/mujoco.md).
"""

from __future__ import annotations

from typing import Any

import mujoco

from . import _coulomb
from ._geoms import IMPEDANCE, MU_MAX
from ._model import KINEMATIC_MASS_RATIO
from ._options import MujocoOptions


def engine_settings(m: mujoco.MjModel, o: MujocoOptions, model_options: bool, h: float, nsteps: int,
                    stack: int) -> dict[str, Any]:  # fmt: skip
    """The settings a trace records: the model file's own options (``model_options``), else the adapter's."""
    if model_options:
        opt = m.opt
        return {
            "engine": f"mujoco {mujoco.__version__}",
            "options": "the model file's own <option> and contact parameters; mujoco.mj_step",
            "timestep": float(opt.timestep),
            "engine_steps_per_step": nsteps,
            "integrator": mujoco.mjtIntegrator(int(opt.integrator)).name,
            "cone": mujoco.mjtCone(int(opt.cone)).name,
            "solver": mujoco.mjtSolver(int(opt.solver)).name,
            "iterations": int(opt.iterations),
            "tolerance": float(opt.tolerance),
        }
    return {
        "engine": f"mujoco {mujoco.__version__}",
        "timestep": h,
        "engine_steps_per_step": nsteps,
        "stack_height": stack,
        "integrator": "implicitfast",
        "cone": "elliptic",
        "solver": "Newton",
        "iterations": int(m.opt.iterations),
        "tolerance": float(m.opt.tolerance),
        "motors": "tendon frictionloss rows (bounded velocity constraints), impedance 0.9999",
        "contact_solref": f"(-erp/h^2, -(1+bounce)/h), erp {o.erp}, bounce_erp {o.bounce_erp}",
        "max_correcting_vel": o.max_correcting_vel,
        "contact_normal_reference": "ODE's for impacts (approach > 1 cm/s) and capped push-outs: "
        f"max(bounce*approach above bounce_vel, min(erp*depth/h, max_correcting_vel {o.max_correcting_vel:g}"
        " m/s)); MuJoCo's from solref for the others",
        "friction_solref": "(-1, -1/h)",
        "friction": f"Coulomb for mu <= {_coulomb.MU_COULOMB:g}: sliding contacts' normal reference corrected "
        f"for the convex cone (at most {_coulomb.MAX_SOLVES} solves per engine step, {_coulomb.TOLERANCE:g} m/s)",
        "impedance": IMPEDANCE,
        "mu_max": MU_MAX,
        "kinematic_mass_ratio": KINEMATIC_MASS_RATIO,
        "bounce_vel": "honoured (the normal row's reference, set before each solve)",
    }
