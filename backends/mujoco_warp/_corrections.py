"""The MuJoCo adapter's engine step on MJWarp's stages: its friction reference, ODE's impact reference and the
Coulomb correction (``backends.mujoco._coulomb``, ``_bounce``), for every world of a device data.

``mujoco_warp.step`` is MuJoCo's step; the MuJoCo adapter's own (``_coulomb.step``) rewrites constraint rows
between MuJoCo's stages. MJWarp exposes the same stages, so the same step is taken here: ``step1`` (positions,
collisions, the constraint rows with their references, velocities), the rows' references rewritten on the host
(the friction rows' damping, ODE's bounce and capped push-out: ``_bounce.normal_reference`` itself, on the
world's rows copied from the device), ``fwd_actuation``, ``fwd_acceleration``, the constraint solve, then the
Coulomb correction's fixed-point iteration (``_coulomb._correct``'s, with ``J*qacc`` from the device's
Jacobian) and the implicitfast integration. Each world iterates on its own contacts and stops on its own test;
a world that has stopped keeps its references, and a solve starts from the step's warm start
(``qacc_warmstart``), so solving it again for the others gives it the same result: a world's step is the one
it takes alone. Differences from the MuJoCo adapter: float32 (MJWarp's); the impedance of a row is computed
from its contact's ``solimp`` (MJWarp keeps no ``efc_KBIP``) and ``R = 1/D``; ``step2``'s acceleration-stage
sensors are not computed (the adapter reads no ``sensordata``; a model file's own options take ``mujoco_warp.step``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..mujoco._bounce import Impacts, normal_reference
from ..mujoco._coulomb import MAX_SOLVES, MU_COULOMB, TOLERANCE, _anderson

#: MuJoCo's bounds on a constraint's impedance (mjMINIMP, mjMAXIMP)
MIN_IMP, MAX_IMP = 0.0001, 0.9999


@dataclass(frozen=True)
class WorldRules:
    """One world's corrections: the friction rows' damping (None: MuJoCo's own) and ODE's impact reference."""

    friction_damping: float | None
    impacts: Impacts | None


@dataclass
class _ContactRows:
    """The fields of ``MjData.contact`` that ``_bounce.normal_reference`` reads, for one world's contacts."""

    efc_address: np.ndarray
    dim: np.ndarray
    solref: np.ndarray
    friction: np.ndarray
    geom1: np.ndarray
    geom2: np.ndarray


@dataclass
class _WorldRows:
    """The fields of ``MjData`` that ``_bounce.normal_reference`` reads and writes, for one world."""

    ncon: int
    contact: _ContactRows
    efc_vel: np.ndarray
    efc_pos: np.ndarray
    efc_margin: np.ndarray
    efc_KBIP: np.ndarray  # noqa: N815 - MjData's name; only its impedance column (2) is filled
    efc_aref: np.ndarray


def _impedance(solimp: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """MuJoCo's impedance of a row at violation ``pos`` (``mj_getImpedance``, as MJWarp's ``_contact_kbimp``)."""
    dmin = np.clip(solimp[:, 0], MIN_IMP, MAX_IMP)
    dmax = np.clip(solimp[:, 1], MIN_IMP, MAX_IMP)
    width = np.maximum(solimp[:, 2], 1e-15)
    mid = np.clip(solimp[:, 3], MIN_IMP, MAX_IMP)
    power = np.maximum(solimp[:, 4], 1.0)
    x = np.minimum(np.abs(pos) / width, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        low = x**power / mid ** (power - 1.0)
        high = 1.0 - (1.0 - x) ** power / (1.0 - mid) ** (power - 1.0)
    y = np.where(power == 1.0, x, np.where(x <= mid, low, high))
    imp = np.clip(dmin + y * (dmax - dmin), np.minimum(dmin, dmax), np.maximum(dmin, dmax))
    return np.where((dmin == dmax) | (solimp[:, 2] <= 1e-15), 0.5 * (dmin + dmax), imp)


class _Iteration:
    """One world's Coulomb correction (``backends.mujoco._coulomb._correct``), one solve at a time."""

    def __init__(self, normal: np.ndarray, mu: np.ndarray, leak: np.ndarray, aref0: np.ndarray, h: float) -> None:
        self.normal, self.mu, self.leak, self.aref0, self.h = normal, mu, leak, aref0, h
        self.c = self.best = np.zeros(normal.size)
        self.best_error = math.inf
        self.history: list[tuple[np.ndarray, np.ndarray]] = []
        self.extra = 0
        self.done = False

    def next(self, jac_t1: np.ndarray, jac_t2: np.ndarray, aref: np.ndarray, force: np.ndarray) -> np.ndarray | None:
        """The normal rows' next references after a solve (``jac_t*``: J*qacc of the friction rows), or None
        when the iteration ends with the references of the solve just made."""
        t1, t2 = self.normal + 1, self.normal + 2
        c = self.c
        g = self.mu * np.hypot(jac_t1 - aref[t1], jac_t2 - aref[t2]) - self.leak * force
        g[(g < 0.0) | ((force <= 0.0) & (c == 0.0))] = 0.0
        f = g - c
        error = float(np.abs(f).max()) * self.h
        if error < self.best_error:
            self.best, self.best_error = c, error
        if error <= TOLERANCE:
            return self._end(None)
        if self.extra + 1 >= MAX_SOLVES:
            return self._end(None if self.best is c else self.aref0 - self.best)
        self.history = [*self.history[-2:], (g, f)]
        self.c = _anderson(self.history)
        self.extra += 1
        return self.aref0 - self.c

    def _end(self, last: np.ndarray | None) -> np.ndarray | None:
        self.done = True
        return last


def _jacobian_rows(wm: Any, wd: Any, world: int, rows: np.ndarray, nv: int, cache: dict[str, Any]) -> np.ndarray:
    """Rows ``rows`` of world ``world``'s constraint Jacobian, dense (len(rows), nv)."""
    if "J" not in cache:
        cache["J"] = wd.efc.J.numpy()
        if wm.is_sparse:
            cache["adr"], cache["nnz"] = wd.efc.J_rowadr.numpy(), wd.efc.J_rownnz.numpy()
            cache["col"] = wd.efc.J_colind.numpy()
    jac = cache["J"]
    if not wm.is_sparse:
        return jac[world, rows, :nv].astype(np.float64)
    out = np.zeros((rows.size, nv))
    adr, nnz, col = cache["adr"][world], cache["nnz"][world], cache["col"][world, 0]
    for i, r in enumerate(rows.tolist()):
        span = slice(adr[r], adr[r] + nnz[r])
        out[i, col[span]] = jac[world, 0, span]
    return out


def step(mjw: Any, wm: Any, wd: Any, rules: Sequence[WorldRules], h: float, impratio: float) -> None:
    """One engine step of every world of ``wd`` with the MuJoCo adapter's corrections (module docstring)."""
    mjw.step1(wm, wd)
    n = int(wd.nacon.numpy()[0])
    aref = None
    if n:
        c = wd.contact
        world_of = c.worldid.numpy()[:n]
        adr = c.efc_address.numpy()[:n, :3]
        if adr.shape[1] < 3:  # no contact with friction rows in the model (condim 1)
            adr = np.pad(adr, ((0, 0), (0, 3 - adr.shape[1])), constant_values=-1)
        dim = c.dim.numpy()[:n]
        friction = c.friction.numpy()[:n].astype(np.float64)
        solref = c.solref.numpy()[:n].astype(np.float64)
        own = c.solreffriction.numpy()[:n]
        solimp = c.solimp.numpy()[:n].astype(np.float64)
        geom = c.geom.numpy()[:n]
        efc = wd.efc
        aref = efc.aref.numpy().astype(np.float64)
        vel = efc.vel.numpy().astype(np.float64)
        pos = efc.pos.numpy().astype(np.float64)
        margin = efc.margin.numpy().astype(np.float64)
        for w in np.unique(world_of).tolist():
            mine = world_of == w
            _references(rules[w], aref[w], vel[w], pos[w], margin[w], adr[mine], dim[mine], friction[mine],
                        solref[mine], own[mine], solimp[mine], geom[mine])  # fmt: skip
        efc.aref.assign(aref.astype(np.float32))
    mjw.fwd_actuation(wm, wd)
    mjw.fwd_acceleration(wm, wd)
    from mujoco_warp._src import solver  # MJWarp's constraint solve (mujoco_warp.step2 calls it; not exported)

    solver.solve(wm, wd)
    if aref is not None:
        iterations = _iterations(wd, aref, world_of, adr, dim, friction, impratio, h)
        if iterations:
            _iterate(wm, wd, solver, iterations, aref)
    if wm.opt.run_rne_postconstraint:
        mjw.rne_postconstraint(wm, wd)
    mjw.implicit(wm, wd)


def _references(rules: WorldRules, aref: np.ndarray, vel: np.ndarray, pos: np.ndarray, margin: np.ndarray,
                adr: np.ndarray, dim: np.ndarray, friction: np.ndarray, solref: np.ndarray, own: np.ndarray,
                solimp: np.ndarray, geom: np.ndarray) -> None:  # fmt: skip
    """One world's references rewritten in ``aref`` as ``_coulomb.step`` rewrites MjData's before its solve."""
    normal = adr[:, 0]
    if rules.friction_damping is not None:  # ``_coulomb._friction_reference``: the rows' position term is 0
        geoms = (normal >= 0) & (dim == 3) & (own[:, 0] == 0.0) & (own[:, 1] == 0.0)
        rows = np.concatenate([adr[geoms, 1], adr[geoms, 2]])
        aref[rows] = -rules.friction_damping * vel[rows]
    if rules.impacts is None:
        return
    kbip = np.zeros((aref.size, 4))
    ok = normal >= 0
    kbip[normal[ok], 2] = _impedance(solimp[ok], pos[normal[ok]] - margin[normal[ok]])
    contact = _ContactRows(normal, dim, solref, friction, geom[:, 0], geom[:, 1])
    rows_view = _WorldRows(normal.size, contact, vel, pos, margin, kbip, aref)
    normal_reference(rows_view, rules.impacts, MU_COULOMB)  # MjData's fields, duck-typed


def _iterations(wd: Any, aref: np.ndarray, world_of: np.ndarray, adr: np.ndarray, dim: np.ndarray,
                friction: np.ndarray, impratio: float, h: float) -> dict[int, _Iteration]:  # fmt: skip
    """The worlds with contacts to correct (``_coulomb.step``'s selection) and their iterations."""
    mu = friction[:, 0]
    keep = (mu <= MU_COULOMB) & (adr[:, 0] >= 0) & (dim == 3)
    if not keep.any():
        return {}
    d = wd.efc.D.numpy()
    out = {}
    for w in np.unique(world_of[keep]).tolist():
        mine = keep & (world_of == w)
        normal = adr[mine, 0]
        mu_w = mu[mine]
        mu_r = mu_w / math.sqrt(impratio)  # MuJoCo's regularised cone (contact.mu)
        leak = mu_r * mu_r / d[w, normal].astype(np.float64)  # R = 1/D
        out[w] = _Iteration(normal, mu_w, leak, aref[w, normal].copy(), h)
    return out


def _iterate(wm: Any, wd: Any, solver: Any, iterations: dict[int, _Iteration], aref: np.ndarray) -> None:
    """Solve again until every world's iteration has ended (each world's rows change only while its own runs)."""
    nv = int(wm.nv)
    cache: dict[str, Any] = {}
    while True:
        qacc = wd.qacc.numpy().astype(np.float64)
        force = wd.efc.force.numpy().astype(np.float64)
        changed = False
        for w, it in iterations.items():
            if it.done:
                continue
            t = np.concatenate([it.normal + 1, it.normal + 2])
            jac = _jacobian_rows(wm, wd, w, t, nv, cache) @ qacc[w, :nv]
            k = it.normal.size
            new = it.next(jac[:k], jac[k:], aref[w], force[w, it.normal])
            if new is not None:
                aref[w, it.normal] = new
                changed = True
        if not changed:
            return
        wd.efc.aref.assign(aref.astype(np.float32))
        solver.solve(wm, wd)
