"""ODE's contact normal row on MuJoCo: bounce above ``bounce_vel`` and a capped penetration push-out.

ODE's contact row asks the step to end with the normal velocity ``max(push, e*approach)`` (the bounce
only when the approach speed before the step exceeds ``bounce_vel``), where ``push = erp*depth/h`` is
capped at the contact max correcting velocity. The model's solref (``_model.contact_solref``) gives
MuJoCo's row ``aref = -B*v - K*I*(pos - margin)``: the bounce *plus* the push-out, for every approach
speed. Before the constraint solve, :func:`normal_reference` rewrites the normal rows whose reference
differs from ODE's (the bouncing surfaces, and the push-outs above the cap) to
``aref = (target - v)/h``: with the constant impedance the row then ends the step at ``target``
(1e-3 of the unconstrained acceleration leaks, ``_model.IMPEDANCE``). ``v`` (``efc_vel``) is the
velocity before the step, as ODE's. Other rows are left as MuJoCo computed them, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np


@dataclass(frozen=True)
class Impacts:
    """What the normal rows need: the step, ERP and cap, and every contact's ``bounce_vel``."""

    h: float
    erp: float
    max_correcting_vel: float
    bounce_vel: float  # the world's surface
    #: (geom1, geom2), geom1 < geom2 -> bounce_vel of a pair with a surface of its own
    pair_bounce_vel: dict[tuple[int, int], float] = field(default_factory=dict)


def normal_reference(d: mujoco.MjData, impacts: Impacts) -> None:
    """Set ODE's reference on the normal rows of this step's contacts (see the module docstring)."""
    n, con = d.ncon, d.contact
    adr = con.efc_address[:n]
    ok = (adr >= 0) & ((con.dim[:n] == 3) | (con.dim[:n] == 1))
    if not ok.any():
        return
    rows = adr[ok]
    h = impacts.h
    e = -con.solref[:n, 1][ok] * h - 1.0  # solref[1] = -(1 + e)/h
    v = d.efc_vel[rows]
    imp = d.efc_KBIP[rows, 2]
    depth = np.maximum(d.efc_margin[rows] - d.efc_pos[rows], 0.0)
    push = impacts.erp * imp * depth / h
    capped = push > impacts.max_correcting_vel
    bouncing = e > 1e-12
    change = capped | bouncing
    if not change.any():
        return
    push = np.minimum(push, impacts.max_correcting_vel)
    threshold = np.full(rows.size, impacts.bounce_vel)
    if impacts.pair_bounce_vel:
        g1, g2 = con.geom1[:n][ok], con.geom2[:n][ok]
        for k in np.flatnonzero(bouncing):
            a, b = int(g1[k]), int(g2[k])
            threshold[k] = impacts.pair_bounce_vel.get((min(a, b), max(a, b)), impacts.bounce_vel)
    approach = -v
    bounce = np.where(bouncing & (approach > threshold), e * approach, 0.0)
    target = np.maximum(push, bounce)
    d.efc_aref[rows[change]] = (target[change] - v[change]) / h
