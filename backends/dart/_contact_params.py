"""DART's contact position correction set to the ODE mapping's: ERP 0.2, push-out capped at 0.1 m/s.

(and 1e-5 m of penetration left uncorrected, so that a resting contact stays detected: ``ERROR_ALLOWANCE``)

A DART ``ContactConstraint`` asks each step for the separating speed ``min(erp * depth / h, max_erv)``
(``getInformation``: the same row as ODE's ``dContactSoftERP`` with ``dWorldSetContactMaxCorrectingVel``).
Its parameters are static members of the C++ class (``ContactConstraint::setErrorReductionParameter``,
``setMaxErrorReductionVelocity``): DART's defaults are ERP 0.01 and, unless a program sets the cap, 1 mm/s
for every island but dense ones of several mobile skeletons touching each other (``ConstraintSolver``:
``kSmallContactIslandMaxErrorReductionVelocity``; ``getMaxErrorReductionVelocity`` reports 0.1 all the
same). With those, a box landing at 3.7 m/s sinks one step of approach (2.7 cm at dt 0.01) and rises at
1 mm/s: 24.3 mm low after 3 s where ODE rests at 0.3 m.

dartpy 6.20 binds neither setter, but both are exported C++ functions of the dartpy module itself
(static members: no ``this``, one ``double``), so they are called through ``ctypes`` by their mangled
names and read back through their getters; a dartpy without them is refused with the reinstall hint,
never run with DART's defaults silently. The values are the ODE adapter's defaults
(``backends/ode/_options.py``: ``erp`` 0.2, ``max_correcting_vel`` 0.1), which the scenario semantics
name (docs/semantics.md: "ERP 0.2 per step, the ODE mapping"; push-out capped). They are process-wide,
so every build sets them again (a run never inherits another's).
"""

from __future__ import annotations

import ctypes
import functools
from importlib.metadata import version

import dartpy as dart

from ..errors import BackendNotInstalled

#: The ODE mapping's global ERP (ODE's default; backends/ode/_options.py ``erp``).
CONTACT_ERP = 0.2
#: The ODE mapping's contact max correcting velocity, m/s (backends/ode/_options.py ``max_correcting_vel``).
MAX_CORRECTING_VEL = 0.1
#: Penetration left uncorrected, m. DART's collider reports a contact point only while it penetrates, and
#: DART's relative CFM (``vel * (1 + cfm)``, not ODE's spring) lets ERP push a resting face out to depth 0,
#: where its corners drop in and out: a box sliding at 2 m/s (conformance 8) reached 1e-9 m after 37 steps
#: of dt 0.01 and then kept 2 of its 4 corners for a step, falling 0.5 mm and tilting. ODE's own soft
#: contact rests at m g / (n kp), kp = erp / (h cfm) = 2e6 N/m per point: 4.9e-6 m for that 4 kg box on 4
#: points, 5.9e-5 m for the 48 kg MJCF box. 1e-5 m is the depth at which the conformance suite starts its
#: resting boxes for the same reason (scenarios/conformance/08_friction.yaml); a resting body sits that
#: much lower than ODE's rigid ideal, far inside every resting-height tolerance (2e-3 m and up).
ERROR_ALLOWANCE = 1e-5

_CLASS = "_ZN4dart10constraint17ContactConstraint"
_SETTERS = {  # mangled name -> (value, getter's mangled name)
    f"{_CLASS}26setErrorReductionParameterEd": (CONTACT_ERP, f"{_CLASS}26getErrorReductionParameterEv"),
    f"{_CLASS}28setMaxErrorReductionVelocityEd": (MAX_CORRECTING_VEL, f"{_CLASS}28getMaxErrorReductionVelocityEv"),
    f"{_CLASS}17setErrorAllowanceEd": (ERROR_ALLOWANCE, f"{_CLASS}17getErrorAllowanceEv"),
}


@functools.cache
def _library() -> ctypes.CDLL:
    return ctypes.CDLL(dart.__file__)


def apply() -> None:
    """Set DART's contact ERP and correction cap to the ODE mapping's and check them through the getters."""
    try:
        lib = _library()
        for setter_name, (value, getter_name) in _SETTERS.items():
            setter, getter = getattr(lib, setter_name), getattr(lib, getter_name)
            setter.argtypes, setter.restype = [ctypes.c_double], None
            getter.argtypes, getter.restype = [], ctypes.c_double
            setter(value)
            if getter() != value:
                raise AttributeError(f"{getter_name} reads {getter()} after setting {value}")
    except (OSError, AttributeError) as exc:
        raise BackendNotInstalled(
            f"Backend `dart` sets ContactConstraint's error reduction (C++ static members of dartpy 6.20); the "
            f"installed dartpy {version('dartpy')} does not provide them ({exc}). Install it with: "
            f"pip install 'dartpy==6.20.*'"
        ) from exc
