"""The surface of one contact joint: its mode, its friction direction (the predicted slip) and an impact's CFM."""

from __future__ import annotations

import math
from typing import Any

from panda3d.core import Vec3
from panda3d.ode import OdeSurfaceParameters, OdeUtil

from ..types import Surface

MODE = OdeSurfaceParameters.MFContactBounce | OdeSurfaceParameters.MFContactApprox1
MODE_FDIR1 = MODE | OdeSurfaceParameters.MFContactFDir1
MODE_SOFT = MODE | OdeSurfaceParameters.MFContactSoftCFM
MODE_SOFT_FDIR1 = MODE_FDIR1 | OdeSurfaceParameters.MFContactSoftCFM
#: Predicted slip speed (m/s) below which a contact keeps its previous friction direction. A body held by
#: friction creeps at CFM * F per contact row (1.75e-5 m/s for 7 N on 4 contacts at CFM 1e-5) and the
#: float32 noise of a resting 4-box column reaches 5.2e-6 m/s (conformance 12, measured): neither has a
#: direction worth following, so the threshold is several times the creep. A tangential load a (m/s^2)
#: shows as h*a in the predicted slip: 1e-4 m/s is a = 0.01 m/s^2 at h 0.01 s (a 0.06 deg tilt), below
#: which the pyramid's direction changes the friction limit only for mu < 1e-3.
SLIP_SPEED = 1e-4
#: An impact's CFM as a fraction of its normal row's inverse mass times h (see ``_contacts.Collider._impact_cfm``).
IMPACT_CFM = 1e-4
#: Approach speed (m/s) above which a contact is an impact and gets :data:`IMPACT_CFM`. A resting body
#: approaches at CFM creep and float noise (< 1e-4 m/s, see :data:`SLIP_SPEED`): it keeps the world's
#: CFM, so resting stacks are the world's. Slower impacts keep it too: their rebound is below 1 cm/s.
IMPACT_SPEED = 0.01


def ode_mu(surface: Surface) -> float:
    return OdeUtil.getInfinity() if math.isinf(surface.mu) else surface.mu


def predicted_slip(body1: Any, body2: Any, geom: Any, kick1: Any, kick2: Any) -> Any:
    """The unit direction of body 1's predicted velocity relative to body 2 at the contact, in its plane.

    Predicted: the point velocity plus the substep's kick h * (F/m + g), what the substep would add
    without contacts (applied torques are left out). None below :data:`SLIP_SPEED`. A static geom has
    no body.
    """
    pos, normal = geom.getPos(), geom.getNormal()
    rel = Vec3(0.0, 0.0, 0.0)
    if body1 is not None:
        rel += body1.getPointVel(pos)
        if kick1 is not None:
            rel += kick1
    if body2 is not None:
        rel -= body2.getPointVel(pos)
        if kick2 is not None:
            rel -= kick2
    rel -= normal * rel.dot(normal)
    speed = rel.length()
    return rel / speed if speed > SLIP_SPEED else None


def approach_speed(body1: Any, body2: Any, geom: Any) -> float:
    """The speed at which the two bodies approach each other at the contact, along its normal (ODE's
    ``-outgoing``: the normal points into body 1)."""
    pos, normal = geom.getPos(), geom.getNormal()
    rel = Vec3(0.0, 0.0, 0.0)
    if body1 is not None:
        rel += body1.getPointVel(pos)
    if body2 is not None:
        rel -= body2.getPointVel(pos)
    return -float(rel.dot(normal))


def surface_parameters(surface: Surface, mode: int, cfm: float = 0.0) -> OdeSurfaceParameters:
    params = OdeSurfaceParameters()
    params.setMode(mode)
    params.setSoftCfm(cfm)
    params.setMu(ode_mu(surface))
    params.setBounce(surface.bounce)
    params.setBounceVel(surface.bounce_vel)
    return params
