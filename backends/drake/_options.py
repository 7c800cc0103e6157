"""The ``backend_options.drake`` block (imports no engine)."""

from __future__ import annotations

from dataclasses import dataclass

from .._kit import BackendOptions, option
from ..errors import UnsupportedFeature

#: MultibodyPlantConfig.contact_model values the adapter offers (docs/backends/drake.md, "Contact model").
CONTACT_MODELS = ("point", "hydroelastic_with_fallback")
#: MultibodyPlantConfig.discrete_contact_approximation values: the convex SAP family only (TAMSI is
#: deprecated in Drake 1.51 and runs no PD-controlled actuator, which the motors are).
APPROXIMATIONS = ("lagged", "sap", "similar")


#: The tallest starting column the backend accepts. Measured (conformance 16, 0.3 m boxes of 13.5 kg, mu 1,
#: dt 0.01, 10 s, hydroelastic modulus 1e6 Pa, SAP): 4, 5 and 7 boxes stand (their compliant contacts sinking
#: the top 3.5, 5.5 and 10.9 mm, as the modulus says; 7 drift 1.8 mm); 8 fall within 7.2 s, and so do 10, 20, 30.
MAX_STACK = 7


def check_stack(stack: int) -> None:
    """Refuse a column taller than Drake is measured to hold standing (:data:`MAX_STACK`)."""
    if stack > MAX_STACK:
        raise UnsupportedFeature(
            f"drake: the world starts with a column of {stack} bodies; Drake is measured to hold at most {MAX_STACK} "
            "standing with its compliant hydroelastic contact (8 boxes of 0.3 m fall within 10 s, "
            "docs/backends/drake.md, Stacking); use dart or mujoco"
        )


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
        1e9, "the velocity motors' PD damping gain Kd (N s/m or N m s/rad); the force is clamped to fmax inside "
        "the solve, so a stiff gain gives ODE's velocity constraint (1e7: the lab door exact to 4 digits)",
        minimum=0.0, min_exclusive=True,
    )  # fmt: skip
