"""The ``backend_options.drake`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option

#: MultibodyPlantConfig.contact_model values the adapter offers (docs/backends/drake.md, "Contact model").
CONTACT_MODELS = ("point", "hydroelastic_with_fallback")
#: MultibodyPlantConfig.discrete_contact_approximation values: the convex SAP family only (TAMSI is
#: deprecated in Drake 1.51 and runs no PD-controlled actuator, which the motors are).
APPROXIMATIONS = ("lagged", "sap", "similar")


@dataclass(frozen=True)
class DrakeOptions(BackendOptions):
    contact_model: str = option(
        "hydroelastic_with_fallback", "hydroelastic_with_fallback (default): moving geometry compliant "
        "hydroelastic, static geometry rigid (a pressure field over the contact patch: a box rests flat and "
        "slides at mu*g); point: one contact point per geometry pair, Drake's cheapest (a box on a plane rests "
        "on one corner and rocks: it slides 19.6 % too far, docs/backends/drake.md)", choices=CONTACT_MODELS,
    )  # fmt: skip
    approximation: str = option(
        "sap", "the discrete contact approximation (Drake's SAP solver): sap (default), lagged or similar",
        choices=APPROXIMATIONS,
    )  # fmt: skip
    penetration_allowance: float = option(
        1e-4, "m: the penetration point contact settles at under a body's weight (Drake derives the contact "
        "stiffness from it; Drake's default is 1e-3)", minimum=0.0, min_exclusive=True,
    )  # fmt: skip
    hydroelastic_modulus: float = option(
        1e6, "Pa: the hydroelastic modulus of compliant geometries (hydroelastic_with_fallback; default 1e6: a "
        "0.3 m box dropped 0.25 m at dt 0.01 lands 2 cm deep and is pushed out; at 1e7 the push-out throws it "
        "1.4 m/s sideways, at 1e8 at 24 m/s)",
        minimum=0.0, min_exclusive=True,
    )  # fmt: skip
    motor_gain: float = option(
        1e7, "the velocity motors' PD damping gain Kd (N s/m or N m s/rad); the force is clamped to fmax inside "
        "the solve, so a stiff gain gives ODE's velocity constraint (1e7: the lab door exact to 4 digits)",
        minimum=0.0, min_exclusive=True,
    )  # fmt: skip
