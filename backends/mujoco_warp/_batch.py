"""Many mujoco_warp worlds as one MJWarp model with ``nworld`` = N (backends.batch, docs/batch.md).

The worlds are built as the single-world adapter builds them (one MuJoCo model and host ``MjData`` each: the
views, ``_view.WorldView``); ``_compare`` checks that they differ only where MJWarp holds a value per world, and
world 0's model goes to the device with those fields batched (``put_model(batch_sizes=...)``, then each world's
row). Each engine step copies every world's qpos, qvel and applied forces up (one copy of each array for all
worlds; the actuators' ctrl and the motors' force limits too when a world changed them), takes one engine step
for all worlds (``_corrections.step``: the MuJoCo adapter's, each world's Coulomb iteration its own) and copies
qpos, qvel and time back (one copy each); contacts, constraint forces and the efc forces are copied only when a
world reads them, once for all worlds per engine step.

A world a step cannot be trusted for (its contacts filled the buffer) is reported by index; the others go on. A
world the runner has ended (``active`` False) is held at its initial state so that it cannot fill the shared
contact buffer of the others (its blow-up, for one, would).
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
from collections.abc import Sequence
from typing import Any, ClassVar

import mujoco
import numpy as np

from ..base import Backend
from ..batch import WorldBatch
from ..errors import EngineFailure, UnsupportedFeature
from ..types import CompiledWorld
from . import _corrections
from ._backend import _WARP_MODULE_LINE, MujocoWarpBackend, _quiet_warp, _solver_tolerance, box_box_as_mujoco
from ._compare import model_differences
from ._view import WorldView


def _world_differences(views: Sequence[WorldView], buffers: bool) -> str | None:
    """What must be equal besides the MuJoCo model: the step, the device (``buffers``: the buffers, which
    follow from the body count, so they are compared after the model's sizes)."""
    first = views[0]
    for k, v in enumerate(views[1:], start=1):
        checks = (
            ("the contact buffer (contacts_per_body x bodies + 8)", v.nconmax, first.nconmax),
            ("the constraint rows per world", v.njmax, first.njmax),
        ) if buffers else (
            ("world.dt", v.world.dt, first.world.dt),
            ("MuJoCo steps per step (world.substeps, engine_substeps)", v.engine_steps, first.engine_steps),
            ("backend_options.mujoco_warp.device", v.options.device, first.options.device),
            ("the model file's own options", v.world.model_options, first.world.model_options),
        )  # fmt: skip
        for what, a, b in checks:
            if a != b:
                return f"{what} is {a!r} in variant {k} and {b!r} in variant 0"
    return None


def _reason(views: Sequence[WorldView]) -> tuple[str | None, set[str]]:
    reason = _world_differences(views, buffers=False)
    if reason is not None:
        return reason, set()
    reason, differ = model_differences([v.model for v in views])
    return (reason, set()) if reason is not None else (_world_differences(views, buffers=True), differ)


def _prepare(m: mujoco.MjModel, d: mujoco.MjData) -> None:
    """What ``mujoco_warp.put_data`` computes on a host MjData before copying it (mujoco_warp 4.0.0 io.py)."""
    mujoco.mj_kinematics(m, d)
    if np.all(d.M == 0):
        mujoco.mj_comPos(m, d)
        mujoco.mj_camlight(m, d)
        mujoco.mj_tendon(m, d)
        mujoco.mj_crb(m, d)
        mujoco.mj_factorM(m, d)


def _assign(array: Any, rows: np.ndarray) -> None:
    """Copy per-world rows into a device array of shape (N, ...) (a vector/matrix dtype: its own shape last)."""
    array.assign(np.ascontiguousarray(rows).reshape(tuple(array.shape) + getattr(array.dtype, "_shape_", ())))


class MujocoWarpBatch(WorldBatch):
    """N mujoco_warp worlds in one MJWarp model (docs/batch.md, "MuJoCo Warp")."""

    backend: ClassVar[type[Backend]] = MujocoWarpBackend

    @classmethod
    def why_not(cls, worlds: Sequence[CompiledWorld]) -> str | None:
        cls._forget()
        if not worlds:
            return "no worlds"
        try:
            views = [WorldView(w, None, i) for i, w in enumerate(worlds)]
        except UnsupportedFeature as exc:
            return str(exc)
        reason = _reason(views)[0]
        if reason is None:  # kept for the batch of these very worlds, usually built next (each build costs ~30 ms)
            cls._accepted = (tuple(worlds), views)
        else:
            for v in views:
                v.close()
        return reason

    #: the worlds ``why_not`` last accepted and their views (one set, handed to the batch built from them)
    _accepted: ClassVar[tuple[tuple[CompiledWorld, ...], list[WorldView]] | None] = None

    @classmethod
    def _forget(cls) -> None:
        if cls._accepted is not None:
            for v in cls._accepted[1]:
                v.close()
            cls._accepted = None

    @classmethod
    def _views_of(cls, worlds: Sequence[CompiledWorld], batch: MujocoWarpBatch) -> list[WorldView]:
        """The views ``why_not`` built for these same world objects, or new ones."""
        kept = cls._accepted
        cls._accepted = None
        if (
            kept is not None
            and len(kept[0]) == len(worlds)
            and all(a is b for a, b in zip(kept[0], worlds, strict=True))
        ):
            for v in kept[1]:
                v.attach(batch)
            return kept[1]
        if kept is not None:
            for v in kept[1]:
                v.close()
        return [WorldView(w, batch, i) for i, w in enumerate(worlds)]

    def __init__(self, worlds: Sequence[CompiledWorld]) -> None:
        super().__init__(worlds)
        self._closed = True  # until built
        if not self.worlds:
            raise ValueError("a batch needs at least one world")
        self.engine_step_count = 0
        self._views = self._views_of(self.worlds, self)
        reason, differ = _reason(self._views)
        if reason is not None:
            self._close_views()
            raise UnsupportedFeature(f"mujoco_warp: these worlds cannot be one batch: {reason}")
        try:
            self._put(differ)
        except NotImplementedError as exc:  # MJWarp's own refusal of a model feature, as the single adapter's
            self._close_views()
            raise UnsupportedFeature(f"mujoco_warp: MJWarp cannot run this world: {exc}") from None
        self._closed = False

    def _put(self, differ: set[str]) -> None:
        import mujoco_warp as mjw

        wp = _quiet_warp()
        views, n = self._views, len(self._views)
        first = views[0]
        m0 = first.model
        self._mjw, self._wp = mjw, wp
        self._device = wp.get_device(first.options.device)
        self._nconmax = first.nconmax
        self._naconmax = n * first.nconmax
        self._motors_changed = False
        self._controls_changed = False
        self._frictionloss_rows = m0.ntendon > 0  # the motors' force limits: set_motor changes them per world
        batched = set(differ) | ({"tendon_frictionloss"} if self._frictionloss_rows else set())
        for v in views[1:]:  # world 0's is prepared by put_data itself
            _prepare(v.model, v.data)
        with wp.ScopedDevice(self._device), contextlib.redirect_stdout(io.StringIO()) as out:
            self._wm = mjw.put_model(m0, batch_sizes={name: n for name in sorted(batched)})
            box_box_as_mujoco(self._wm)
            self._wd = mjw.put_data(m0, first.data, nworld=n, nconmax=first.nconmax, njmax=first.njmax)
            for name in sorted(batched):
                _assign(getattr(self._wm, name), np.stack([getattr(v.model, name) for v in views]))
            self._per_world_data()
            tolerance = self._wm.opt.tolerance  # the single adapter's stopping rule, per world (_solver_tolerance)
            per_world = np.array([_solver_tolerance(v.model, v.data) for v in views])
            self._wm.opt.tolerance = wp.array(per_world, dtype=tolerance.dtype, device=self._device)
            self._wm.opt.tolerance._is_batched = True
        self._messages(out)
        self.qpos = np.stack([v.data.qpos for v in views])
        self.qvel = np.stack([v.data.qvel for v in views])
        self.time = np.array([v.data.time for v in views])
        self._xfrc = np.zeros((n, m0.nbody, 6))
        self._rules = [v.rules for v in views]
        self._start_qpos = self.qpos.copy()
        self._cache: dict[str, Any] = {}

    def _per_world_data(self) -> None:
        """Data fields that differ between the worlds' host MjData (``put_data`` copied world 0's to all)."""
        from mujoco_warp._src import types

        datas = [v.data for v in self._views]
        for f in dataclasses.fields(types.Data):
            shape = getattr(f.type, "shape", ())
            if not shape or shape[0] != "nworld" or not hasattr(datas[0], f.name):
                continue
            first = np.asarray(getattr(datas[0], f.name)).tobytes()
            if all(np.asarray(getattr(d, f.name)).tobytes() == first for d in datas[1:]):
                continue
            target = getattr(self._wd, f.name)
            rows = np.stack([np.asarray(getattr(d, f.name)) for d in datas])
            if rows.size != target.size * int(np.prod(getattr(target.dtype, "_shape_", ()))):
                continue  # laid out MJWarp's own way (the factorised mass matrix): recomputed by every step
            _assign(target, rows)

    def _messages(self, out: io.StringIO, active: np.ndarray | None = None) -> None:
        """What MJWarp printed about the batch (not Warp's compile lines: see the single adapter's ``_keep``) goes
        to every active world's messages."""
        lines = [line for line in out.getvalue().splitlines() if line.strip() and not _WARP_MODULE_LINE.match(line)]
        if lines:
            for i, v in enumerate(self._views):
                if active is None or active[i]:
                    v.add_messages(list(lines))

    # --- WorldBatch ---------------------------------------------------------------------------------------

    @property
    def views(self) -> Sequence[Backend]:
        return self._views

    def motors_changed(self) -> None:
        self._motors_changed = True

    def controls_changed(self) -> None:
        """A world's actuator ctrl changed on its host MjData (``set_control``)."""
        self._controls_changed = True

    def step_all(self, active: Sequence[bool]) -> dict[int, EngineFailure]:
        if self._closed:
            raise RuntimeError("step_all() called after close()")
        views = self._views
        if len(active) != len(views):
            raise ValueError(f"step_all: {len(active)} flags for {len(views)} worlds")
        on = np.asarray(active, dtype=bool)
        idle = ~on
        if idle.any():  # ended worlds: held where they started, so that they cannot flood the others
            self.qpos[idle] = self._start_qpos[idle]
            self.qvel[idle] = 0.0
            self._xfrc[idle] = 0.0
        if self._motors_changed:
            _assign(self._wm.tendon_frictionloss, np.stack([v.model.tendon_frictionloss for v in views]))
            self._motors_changed = False
        if self._controls_changed:  # each world's own ctrl, held on the device until changed (as MjData's)
            _assign(self._wd.ctrl, np.stack([v.data.ctrl for v in views]))
            self._controls_changed = False
        busy = [v for i, v in enumerate(views) if on[i] and v.busy()]
        failures: dict[int, EngineFailure] = {}
        for v in busy:
            v.begin()
        nsteps = views[0].engine_steps
        for k in range(nsteps):
            for v in busy:
                v.before(k)
                i, d = v.index, v.data
                self.qpos[i] = d.qpos
                self.qvel[i] = d.qvel
                self._xfrc[i] = d.xfrc_applied
            self._engine_step(on, failures)
            for v in busy:
                v.sync()
                v.after(k)
        for v in busy:
            v.end()
            i, d = v.index, v.data
            self.qpos[i], self.qvel[i], self._xfrc[i] = d.qpos, d.qvel, d.xfrc_applied
        for i, v in enumerate(views):
            if on[i]:
                v.stepped(failures.get(i))
        return failures

    def _engine_step(self, on: np.ndarray, failures: dict[int, EngineFailure]) -> None:
        wd = self._wd
        wd.qpos.assign(self.qpos)
        wd.qvel.assign(self.qvel)
        _assign(wd.xfrc_applied, self._xfrc)
        first = self._views[0]
        with contextlib.redirect_stdout(io.StringIO()) as out:
            if first.world.model_options:  # the model files' own options (equal in all worlds): MuJoCo's step
                self._mjw.step(self._wm, wd)
            else:
                _corrections.step(self._mjw, self._wm, wd, self._rules, first.engine_h, first.model.opt.impratio)
        self._messages(out, on)
        self.qpos = wd.qpos.numpy().astype(np.float64)
        self.qvel = wd.qvel.numpy().astype(np.float64)
        self.time = wd.time.numpy().astype(np.float64)
        self.engine_step_count += 1
        self._cache = {}
        total = int(wd.nacon.numpy()[0])
        if total >= self._nconmax:  # some world may have filled its share: count them
            self._overflows(total, on, failures)

    def _overflows(self, total: int, on: np.ndarray, failures: dict[int, EngineFailure]) -> None:
        """The single adapter's verdict (a world's contacts reached the buffer), per world; a full shared buffer
        may have dropped anyone's contacts, so then every world fails."""
        counts = np.bincount(self._wd.contact.worldid.numpy()[:total], minlength=len(self._views))
        full = total >= self._naconmax
        for i in np.flatnonzero(on & ((counts >= self._nconmax) | full)).tolist():
            if i in failures:
                continue
            v = self._views[i]
            t = (v.steps + 1) * v.world.dt
            shared = " (the batch's shared buffer filled)" if full else ""
            failures[i] = EngineFailure(
                f"mujoco_warp: the contact buffer ({self._nconmax} contacts) filled up by t={t:g} s{shared}, so "
                "contacts were dropped; raise backend_options.mujoco_warp.contacts_per_body",
                backend=MujocoWarpBackend.name,
                time=t,
            )

    # --- reads for the views: one copy for all worlds per engine step ----------------------------------

    def constraint_forces(self, world: int) -> np.ndarray:
        rows = self._cache.get("qfrc")
        if rows is None:
            rows = self._cache["qfrc"] = self._wd.qfrc_constraint.numpy().astype(np.float64)
        return rows[world]

    def contacts_of(self, world: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """World ``world``'s contacts of the last engine step, in MJWarp's order: distance, geoms, first efc row,
        and the world's efc forces."""
        cached = self._cache.get("contacts")
        if cached is None:
            wd = self._wd
            n = int(wd.nacon.numpy()[0])
            c = wd.contact
            owner = c.worldid.numpy()[:n]
            order = np.argsort(owner, kind="stable")
            bounds = np.searchsorted(owner[order], np.arange(len(self._views) + 1))
            cached = self._cache["contacts"] = (
                c.dist.numpy()[:n][order], c.geom.numpy()[:n][order], c.efc_address.numpy()[:n, 0][order], bounds,
                wd.efc.force.numpy(),
            )  # fmt: skip
        dist, geom, rows, bounds, efc = cached
        lo, hi = bounds[world], bounds[world + 1]
        return dist[lo:hi], geom[lo:hi], rows[lo:hi], efc[world]

    def reaction_rows(self, world: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(cfrc_int, subtree_com, xipos) of world ``world`` after MJWarp's ``rne_postconstraint`` (run once for
        all worlds per engine step), as the single adapter reads them."""
        rows = self._cache.get("reactions")
        if rows is None:
            wd = self._wd
            self._mjw.rne_postconstraint(self._wm, wd)
            rows = self._cache["reactions"] = (wd.cfrc_int.numpy(), wd.subtree_com.numpy(), wd.xipos.numpy())
        cfrc, com, xipos = rows
        return cfrc[world].astype(np.float64), com[world].astype(np.float64), xipos[world].astype(np.float64)

    def contact_points_of(self, world: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """World ``world``'s touching contacts of the last engine step, in MJWarp's order: geoms, positions,
        normals, distances and normal forces (``mujoco_warp.contact_force``, as the single adapter reads them)."""
        wd = self._wd
        n = int(wd.nacon.numpy()[0])
        c = wd.contact
        dist = c.dist.numpy()[:n].astype(np.float64)
        keep = np.flatnonzero((c.worldid.numpy()[:n] == world) & (dist <= 0.0))
        if keep.size == 0:
            empty = np.zeros((0, 3))
            return np.zeros((0, 2), dtype=np.int64), empty, empty, np.zeros(0), np.zeros(0)
        wp = self._wp
        ids = wp.array(keep.astype(np.int32), dtype=wp.int32, device=self._device)
        wrench = wp.zeros(keep.size, dtype=wp.spatial_vector, device=self._device)
        self._mjw.contact_force(self._wm, wd, ids, False, wrench)
        force = wrench.numpy()[:, 0].astype(np.float64)
        pos = c.pos.numpy()[keep].astype(np.float64)
        normal = c.frame.numpy()[keep, 0, :].astype(np.float64)
        return c.geom.numpy()[keep], pos, normal, dist[keep], force

    # --- closing ------------------------------------------------------------------------------------------

    def _close_views(self) -> None:
        for v in self._views:
            v.close()

    def close(self) -> None:
        if getattr(self, "_closed", True):
            if hasattr(self, "_views"):
                self._close_views()
            return
        self._closed = True
        self._close_views()
        self._wm = self._wd = None
        self._cache = {}
