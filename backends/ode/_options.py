"""The ``backend_options.ode`` block: keys, defaults (ODE's own) and validation.

Defaults are the lab's: ``world.step`` (the accurate "big matrix" stepper), ERP 0.2 and CFM 1e-5, the
values ``dWorldCreate`` sets in this single-precision build. CFM 1e-10 (double-precision ODE's default)
makes this build's LCP fail ("LCP internal error, s <= 0") and the lab scene fly apart; 1e-9 failed
too and 1e-8 was the smallest value that stayed sound on it, so smaller values are refused.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..errors import UnsupportedFeature

#: Smallest accepted CFM (measured on the lab scene, see the module docstring).
MIN_CFM = 1e-8

OPTION_KEYS: Mapping[str, str] = {
    "stepper": "step (dWorldStep, accurate, the default) or quickstep (dWorldQuickStep, iterative)",
    "quickstep_iterations": "iterations of quickstep's SOR solver (ODE default 20)",
    "erp": "global error reduction parameter, 0..1 (ODE default 0.2)",
    "cfm": f"global constraint force mixing, >= {MIN_CFM:g} (default 1e-5, single-precision ODE's)",
    "space": "collision space: simple (the lab's, the default) or hash",
    "collide": "auto (contacts made in C++ by OdeSpace.autoCollide, the default) or callback "
    "(the lab's Python near-callback with OdeUtil.collide; slower, same contacts)",
    "contact_forces": "true (default): joint feedback on the last substep's contact joints gives "
    "Contact.normal_force; false: NaN, and no per-contact Python work",
}


@dataclass(frozen=True)
class OdeOptions:
    stepper: str = "step"
    quickstep_iterations: int = 20
    erp: float = 0.2
    cfm: float = 1e-5
    space: str = "simple"
    collide: str = "auto"
    contact_forces: bool = True


def _choice(raw: Mapping[str, Any], key: str, default: str, allowed: tuple[str, ...]) -> str:
    value = raw.get(key, default)
    if value not in allowed:
        raise UnsupportedFeature(
            f"Invalid `backend_options.ode.{key}`. Expected one of {', '.join(allowed)}. Received: {value!r}."
        )
    return str(value)


def _number(raw: Mapping[str, Any], key: str, default: float, lo: float, hi: float) -> float:
    value = raw.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UnsupportedFeature(f"Invalid `backend_options.ode.{key}`. Expected a number. Received: {value!r}.")
    if not lo <= value <= hi:
        raise UnsupportedFeature(
            f"Invalid `backend_options.ode.{key}`. Expected {lo:g} <= {key} <= {hi:g}. Received: {value!r}."
        )
    return float(value)


def parse_options(raw: Mapping[str, Any]) -> OdeOptions:
    """Validate the option block (unknown keys were already refused by the registry)."""
    iterations = raw.get("quickstep_iterations", 20)
    if isinstance(iterations, bool) or not isinstance(iterations, int) or iterations < 1:
        raise UnsupportedFeature(
            "Invalid `backend_options.ode.quickstep_iterations`. Expected an integer >= 1. "
            f"Received: {iterations!r}."
        )
    forces = raw.get("contact_forces", True)
    if not isinstance(forces, bool):
        raise UnsupportedFeature(
            f"Invalid `backend_options.ode.contact_forces`. Expected true or false. Received: {forces!r}."
        )
    return OdeOptions(
        stepper=_choice(raw, "stepper", "step", ("step", "quickstep")),
        quickstep_iterations=iterations,
        erp=_number(raw, "erp", 0.2, 0.0, 1.0),
        cfm=_number(raw, "cfm", 1e-5, MIN_CFM, 1.0),
        space=_choice(raw, "space", "simple", ("simple", "hash")),
        collide=_choice(raw, "collide", "auto", ("auto", "callback")),
        contact_forces=forces,
    )
