"""One MuJoCo engine step with Coulomb friction: the sliding contacts' normal reference corrected.

MuJoCo solves its contacts as one convex problem. For an elliptic contact the optimum puts a contact
that slides on the dual cone: ``jar_n = mu*|jar_t|``, where ``jar = J*qacc - aref`` per row. The
friction rows ask for ``aref_t = -v_t/h`` (stop the slip in one step, as ODE's friction rows do); a
sliding contact cannot meet that, ``jar_t = v_t'/h`` (``v_t'``: the slip at the end of the step), so
its normal row ends ``mu*|v_t'|/h`` above its own reference: the body is pushed off the surface by
``mu*|v_t'|`` in the step (0.38 m/s for a box launched at 2 m/s, mu 0.5, dt 0.01), and Coulomb's bound
then acts on that inflated normal force. Any friction rate does it (a slower one trades the push for
friction that cannot stop a slip), and so does the pyramidal cone.

``step`` removes that term. After a constraint solve it lowers the normal reference of each sliding
contact by ``c = mu*|jar_t| - mu_r^2*R*f_n`` and solves again, until ``c`` is a fixed point. There the
normal row meets its own reference (ERP push-out or bounce, as ODE's) with the softness of a contact
without friction (the second term: MuJoCo's middle zone is ``1 + mu_r^2`` times softer along the
normal), the friction force is ``mu*N`` against the end-of-step slip (ODE's ``dContactApprox1``), and a
contact that can stick sticks (its slip, and with it ``c``, goes to 0). The plain iteration contracts by
about ``mu^2/(1+mu^2)`` per solve for a box on a plane; Anderson acceleration reaches the tolerance in
one or two more solves. Without sliding contacts the calls are those of ``mj_step``, in its order: bit
for bit the same step. docs/backends/mujoco.md has the measurements.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ._bounce import Impacts, normal_reference

#: Constraint solves per engine step at most (the first one included), plus one to return to the best
#: correction seen when the iteration has not converged by then.
MAX_SOLVES = 12
#: Stop when no contact's correction changes its normal velocity by more than this in a step (m/s).
TOLERANCE = 1e-6
#: Contacts with a larger friction coefficient keep MuJoCo's cone: the fixed point's slope is about
#: mu^2/(1 + mu^2), so above this it is too ill-conditioned to find, and such contacts stick anyway.
MU_COULOMB = 20.0


def step(
    m: mujoco.MjModel, d: mujoco.MjData, friction_damping: float | None = None, impacts: Impacts | None = None
) -> int:
    """``mj_step`` with the sliding contacts' normal reference corrected; returns the solves made.

    ``friction_damping``: when given, the friction rows of contacts made from geoms (which take MuJoCo's
    normal solref, having no friction solref of their own) ask for ``aref = -friction_damping * v``, what
    a contact pair's ``solreffriction`` gives (``_model.Layout.friction_damping``). ``impacts``: when
    given, the normal rows get ODE's bounce and capped push-out (``_bounce.normal_reference``).
    """
    mujoco.mj_step1(m, d)
    if friction_damping is not None and d.ncon:
        _friction_reference(d, friction_damping)
    if impacts is not None and d.ncon:
        normal_reference(d, impacts, MU_COULOMB)
    mujoco.mj_fwdActuation(m, d)
    mujoco.mj_fwdAcceleration(m, d)
    mujoco.mj_fwdConstraint(m, d)
    solves = 1
    n = d.ncon
    if n:
        con = d.contact
        mu = con.friction[:n, 0]
        keep = mu <= MU_COULOMB
        if keep.any():  # else no contact is corrected (cheapest test first)
            adr = con.efc_address[:n]
            keep &= (adr >= 0) & (con.dim[:n] == 3)  # the adapter's contacts: condim 3 or 1
            if keep.any():
                solves += _correct(m, d, adr[keep], mu[keep], con.mu[:n][keep])
    mujoco.mj_checkAcc(m, d)
    mujoco.mj_implicit(m, d)  # mj_step's integrator for implicitfast
    return solves


def _friction_reference(d: mujoco.MjData, b: float) -> None:
    """Redo ``mj_referenceConstraint``'s ``aref = -B*v - K*I*(pos - margin)`` with ``B = b`` on the friction
    rows of the contacts without a friction solref of their own (those from geoms, not from pairs)."""
    n, con = d.ncon, d.contact
    adr = con.efc_address[:n]
    own = con.solreffriction[:n]
    geoms = adr[(adr >= 0) & (con.dim[:n] == 3) & (own[:, 0] == 0.0) & (own[:, 1] == 0.0)]
    if geoms.size:
        rows = np.concatenate([geoms + 1, geoms + 2])  # elliptic cone: the normal row, then the friction rows
        kbip = d.efc_KBIP[rows]
        d.efc_aref[rows] = -b * d.efc_vel[rows] - kbip[:, 0] * kbip[:, 2] * (d.efc_pos[rows] - d.efc_margin[rows])


def _correct(m: mujoco.MjModel, d: mujoco.MjData, normal: np.ndarray, mu: np.ndarray, mu_r: np.ndarray) -> int:
    """Iterate the correction of the normal rows ``normal`` to its fixed point; returns the extra solves.

    ``mu`` is each contact's friction coefficient (the adapter's pairs are isotropic), ``mu_r`` MuJoCo's
    regularised one. ``g(c)`` is the correction that the solve with correction ``c`` asks for and
    ``g - c`` each contact's normal acceleration error; contacts without a normal force (separating)
    need none unless they had one. Anderson acceleration of depth 2 extrapolates ``c`` from the last
    three solves: a box's contacts share its slip but not its load, so they move in more than one mode.
    """
    h = m.opt.timestep
    aref = d.efc_aref
    aref0 = aref[normal].copy()
    t1, t2 = normal + 1, normal + 2
    leak = mu_r * mu_r * d.efc_R[normal]
    jac = np.empty(d.nefc)
    c = best = np.zeros(normal.size)
    best_error = math.inf
    history: list[tuple[np.ndarray, np.ndarray]] = []  # (g, g - c) of the last solves
    extra = 0
    while True:
        mujoco.mj_mulJacVec(m, d, jac, d.qacc)
        force = d.efc_force[normal]
        g = mu * np.hypot(jac[t1] - aref[t1], jac[t2] - aref[t2]) - leak * force
        g[(g < 0.0) | ((force <= 0.0) & (c == 0.0))] = 0.0
        f = g - c
        error = float(np.abs(f).max()) * h  # the worst normal velocity error of the step, m/s
        if error < best_error:
            best, best_error = c, error
        if error <= TOLERANCE:
            return extra
        if extra + 1 >= MAX_SOLVES:  # not converged: end on the best correction seen (c = 0: MuJoCo's own)
            if best is not c:
                aref[normal] = aref0 - best
                mujoco.mj_fwdConstraint(m, d)
                extra += 1
            return extra
        history = [*history[-2:], (g, f)]
        c = _anderson(history)
        aref[normal] = aref0 - c
        mujoco.mj_fwdConstraint(m, d)
        extra += 1


def _anderson(history: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Next correction: ``g - dG*gamma`` with ``gamma`` minimising ``|f - dF*gamma|`` (plain ``g`` first)."""
    g, f = history[-1]
    if len(history) == 1:
        return g
    dg = [g - gi for gi, _ in history[:-1]]
    df = [f - fi for _, fi in history[:-1]]
    if len(df) == 1:
        a = float(df[0] @ df[0])
        return g - dg[0] * (float(df[0] @ f) / a) if a > 0.0 else g
    a11, a12, a22 = float(df[0] @ df[0]), float(df[0] @ df[1]), float(df[1] @ df[1])
    b1, b2 = float(df[0] @ f), float(df[1] @ f)
    det = a11 * a22 - a12 * a12
    if det <= 1e-12 * a11 * a22:  # the two differences are (nearly) parallel: use the newer one
        return g - dg[1] * (b2 / a22) if a22 > 0.0 else g
    return g - dg[0] * ((b1 * a22 - b2 * a12) / det) - dg[1] * ((b2 * a11 - b1 * a12) / det)
