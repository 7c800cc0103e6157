"""ODE's contact normal row on MuJoCo for impacts: bounce above ``bounce_vel``, a capped push-out.

ODE's contact row asks the step to end with the normal velocity ``max(push, e*approach)`` (the bounce
only when the approach speed before the step exceeds ``bounce_vel``), where ``push = erp*depth/h`` is
capped at the contact max correcting velocity. The model's solref (``_geoms.contact_solref``,
``(-erp/h^2, -(1+e)/h)``) gives MuJoCo's row ``aref = -B*v - K*I*(pos - margin)``, which ends the step
at ``-e*v + push``: the bounce *plus* the push-out, whatever ``bounce_vel``, and an uncapped push-out.
Before the constraint solve, :func:`normal_reference` rewrites to ``aref = (target - v)/h`` the normal
rows of impacts (a bouncing surface approached faster than :data:`IMPACT_SPEED`) and of push-outs
above the cap: with the constant impedance the row then ends the step at ``target`` (1e-3 of the
unconstrained acceleration leaks, ``_geoms.IMPEDANCE``). ``v`` (``efc_vel``) is the velocity before
the step, as ODE's. A bouncing surface's slower contacts (resting ones) keep MuJoCo's reference with
``bounce_erp`` (their bounce is below ``e`` cm/s), as before issue 17, unless deeper than 3 times the
depth at which that reference holds a resting body (``Impacts.rest``, from the 1e-3 leak): a landing's
penetration, which ODE's bounce leaves in, is then pushed out at ODE's ``erp``, capped, when that is
faster (``bounce_erp`` alone recovers 5 % of it per step).

Contacts whose friction is MuJoCo's own cone (mu above ``_coulomb.MU_COULOMB``, not corrected) keep
MuJoCo's normal row, push-out uncapped, less the bounce below ``bounce_vel``: their normal row already
carries the cone's push ``mu*|jar_t|`` (the lab's box, mu 5000, hopped on its door at each change of the
door's motion with ODE's row, measured), so ODE's reference would not be ODE's contact there
(docs/backends/mujoco.md). A world's parameters for it: :func:`impacts_of`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from ..types import CompiledWorld
from ._geoms import IMPEDANCE
from ._options import MujocoOptions

#: Approach speed (m/s) above which a bouncing contact is an impact and gets ODE's reference.
IMPACT_SPEED = 0.01


@dataclass(frozen=True)
class Impacts:
    """What the normal rows need: the step, the push-out cap and every contact's ``bounce_vel``."""

    h: float
    erp: float  # ODE's, for the push-out of deep contacts of bouncing surfaces
    max_correcting_vel: float
    rest: float  # depth (m) a bouncing surface's resting contact keeps: (1 - impedance)*|g|*h^2/bounce_erp
    bounce_vel: float  # the world's surface
    #: (geom1, geom2), geom1 < geom2 -> bounce_vel of a pair with a surface of its own
    pair_bounce_vel: dict[tuple[int, int], float] = field(default_factory=dict)


def normal_reference(d: mujoco.MjData, impacts: Impacts, mu_coulomb: float) -> None:
    """Set ODE's reference on the normal rows of impacts and capped push-outs (module docstring);
    contacts with mu above ``mu_coulomb`` have MuJoCo's cone."""
    n, con = d.ncon, d.contact
    adr = con.efc_address[:n]
    ok = (adr >= 0) & ((con.dim[:n] == 3) | (con.dim[:n] == 1))
    if not ok.any():
        return
    rows = adr[ok]
    h = impacts.h
    solref = con.solref[:n][ok]
    e = -solref[:, 1] * h - 1.0  # solref = (-erp/h^2, -(1 + e)/h)
    v = d.efc_vel[rows]
    approach = -v
    depth = np.maximum(d.efc_margin[rows] - d.efc_pos[rows], 0.0)
    cap = impacts.max_correcting_vel
    imp = d.efc_KBIP[rows, 2]
    push = -solref[:, 0] * h * imp * depth  # the row's own: K*I*depth*h with K = erp/h^2
    bouncing = e > 1e-12
    coulomb = con.friction[:n, 0][ok] <= mu_coulomb
    capped = (push > cap) & (coulomb | ~bouncing)
    impact = bouncing & (approach > IMPACT_SPEED)
    deep = bouncing & coulomb & ~impact & (depth > 3.0 * impacts.rest)
    if not (capped.any() or impact.any() or deep.any()):
        return
    threshold = np.full(rows.size, impacts.bounce_vel)
    if impacts.pair_bounce_vel:
        g1, g2 = con.geom1[:n][ok], con.geom2[:n][ok]
        for k in np.flatnonzero(impact):
            a, b = int(g1[k]), int(g2[k])
            threshold[k] = impacts.pair_bounce_vel.get((min(a, b), max(a, b)), impacts.bounce_vel)
    above = approach > threshold
    cone = impact & ~coulomb & ~above  # MuJoCo's cone row, only its bounce removed below bounce_vel
    change = capped | (impact & coulomb) | deep | cone
    if not change.any():
        return
    own = -e * v + np.minimum(push, cap)  # MuJoCo's end-of-step velocity, its push-out capped
    ode = np.minimum(impacts.erp * imp * depth / h, cap)
    bounce = np.where(above, e * approach, 0.0)
    target = np.where(impact & coulomb, np.maximum(ode, bounce), np.where(deep, np.maximum(ode, own), own))
    target = np.where(cone, push, target)
    d.efc_aref[rows[change]] = (target[change] - v[change]) / h


def impacts_of(world: CompiledWorld, m: mujoco.MjModel, h: float, o: MujocoOptions) -> Impacts:
    """The normal rows' parameters: the world's bounce_vel and the pairs' own (by MuJoCo geom id)."""
    pairs: dict[tuple[int, int], float] = {}
    for pair in world.pair_surfaces:
        try:  # a primitive body's one geom (a compound body's geoms keep the world's bounce_vel)
            a, b = m.geom(f"geom:{pair.a}").id, m.geom(f"geom:{pair.b}").id
        except KeyError:
            continue
        pairs[(min(a, b), max(a, b))] = pair.surface.bounce_vel
    rest = (1.0 - IMPEDANCE) * math.hypot(*world.gravity) * h * h / o.bounce_erp
    return Impacts(h, o.erp, o.max_correcting_vel, rest, world.default_surface.bounce_vel, pairs)
