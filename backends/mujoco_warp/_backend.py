"""The MuJoCo Warp adapter: the MuJoCo adapter's model and inputs, each engine step taken by ``mujoco_warp``.

The world is built exactly as the MuJoCo backend builds it (``backends.mujoco._model.build``: the same MjModel,
ODE's mapping of motors, stops, surfaces and kinematic bodies), copied to a Warp device with
``mujoco_warp.put_model``/``put_data`` (one world) and stepped on MJWarp's stages. What differs from the
MuJoCo backend, and why (docs/backends/mujoco_warp.md):

* the engine step is the MuJoCo adapter's (``backends.mujoco._coulomb.step``: its friction reference, ODE's impact
  reference and the Coulomb correction between MuJoCo's stages) taken on MJWarp's stages (``_corrections``);
  a model file's own options get ``mujoco_warp.step``, MuJoCo's own, as on the MuJoCo backend;
* float32 (``Precision.FLOAT32``), and the solver's stopping rule rescaled to MuJoCo's (``_solver_tolerance``);
* the state is copied host <-> device around each engine step, so the poses and velocities are read as the
  MuJoCo adapter reads them (on the host MjData); contacts, constraint forces and joint reactions come from the
  device data.
"""

from __future__ import annotations

import contextlib
import io
import re
from typing import Any, ClassVar

import mujoco
import numpy as np

from .._kit import BackendOptions, contact_point, group_by_pair, sorted_points
from .._kit.quiet import keep_warp_cache_outside, silenced_output
from ..errors import EngineFailure, UnsupportedFeature
from ..mujoco._backend import MujocoBackend
from ..types import Capability, CompiledWorld, Contact, ContactPoint, Precision
from . import _corrections
from ._options import MujocoWarpOptions

#: Constraint rows per world for each allowed contact (an elliptic contact's 3 rows) and per dof (limits,
#: friction loss, the motors' rows), plus a margin.
ROWS_PER_CONTACT = 3
ROWS_PER_DOF = 2
_WARP_MODULE_LINE = re.compile(r"^(Module \S+ \S+ load on device|Warp \d|   )")
#: Warp's kernel cache, outside the repository (a first compile takes 20-100 s per new kind of scene; the
#: environment's WARP_CACHE_PATH wins)
keep_warp_cache_outside()


def _quiet_warp() -> Any:
    """Import Warp with its banner, its per-module compile lines and its missing-driver warning (a CPU run's
    normal case; a CUDA device it cannot see is refused by name, ``_check_cuda``) kept out of the terminal."""
    with silenced_output():
        import warp as wp

        wp.config.quiet = True
        wp.config.verbose = False
        wp.init()
    return wp


#: MJWarp's own floor on the solver tolerance (mujoco_warp.put_model: MuJoCo's default is meant for float64)
FLOAT32_TOLERANCE = 1e-6


def _solver_tolerance(m: mujoco.MjModel, d: mujoco.MjData) -> float:
    """The tolerance that gives MJWarp MuJoCo's stopping rule.

    MuJoCo scales its convergence test by ``1/(stat.meaninertia * nv)``, and the MuJoCo adapter sets
    ``meaninertia`` from the dynamic bodies (``_model._rescale_solver``). MJWarp scales it by ``1/trace(M)``
    of each step, where the motor helpers and kinematic bodies (a million times the heaviest body) dominate:
    its solver stopped after one Newton iteration, short of a motor row's quadratic zone (a hinge motor reached
    0.9918 of its target in the step it should have reached it). ``tolerance * meaninertia * nv / trace(M)``
    restores MuJoCo's test; the heavy bodies are free bodies or slides, whose diagonal does not change with the
    pose (a free joint's rotational dofs are in the body frame), so the start's trace holds."""
    start = mujoco.MjData(m)
    start.qpos[:] = d.qpos
    mujoco.mj_forward(m, start)
    trace = float(start.M[m.M_rowadr + m.M_rownnz - 1].sum())
    base = max(float(m.opt.tolerance), FLOAT32_TOLERANCE)
    return base * float(m.stat.meaninertia) * max(1, m.nv) / max(trace, mujoco.mjMINVAL)


def box_box_as_mujoco(wm: Any) -> None:
    """Box-box contacts by MJWarp's analytic collider, MuJoCo's ``mjc_BoxBox``, not its default convex (GJK/EPA)
    path, which misses contacts a box on a larger box has (a 0.1 m cube 1.2 mm into a 4 x 4 x 0.1 m box: no
    contact, where MuJoCo finds 4, and the cube fell through; mujoco_warp issues 1430 and 1526). MJWarp reads the
    flag when it collides (``collision_driver._narrowphase``); the host model is left as it is."""
    from mujoco_warp._src.types import DisableBit

    wm.opt.disableflags = int(wm.opt.disableflags) | int(DisableBit.NATIVECCD)


def _check_cuda(device: str) -> None:
    """Refuse a CUDA device that Warp does not see, before anything is built."""
    wp = _quiet_warp()
    count = wp.get_cuda_device_count()
    index = int(device.partition(":")[2] or 0)
    if index >= count:
        seen = f"{count} CUDA device{'s' if count != 1 else ''}" if count else "no CUDA device (no driver or GPU)"
        raise UnsupportedFeature(
            f"mujoco_warp: backend_options.mujoco_warp.device `{device}`: Warp sees {seen} on this machine; "
            "use `device: cpu`"
        )


class MujocoWarpBackend(MujocoBackend):
    """MuJoCo's model stepped by MJWarp on a Warp device (docs/backends/mujoco_warp.md)."""

    name: ClassVar[str] = "mujoco_warp"
    engine_distribution: ClassVar[str] = "mujoco-warp"
    precision: ClassVar[Precision] = Precision.FLOAT32  # MJWarp computes in float32
    #: what the MuJoCo backend runs but MJWarp does not: model files' own options (MJWarp refuses the PGS
    #: solver, noslip and contact overrides a file may hold), and an MJCF file's extras are not checked here yet
    capabilities: ClassVar[frozenset[Capability]] = MujocoBackend.capabilities - {
        Capability.CONSTRAINT_TENDON,
        Capability.CONSTRAINT_EQUALITY,
        Capability.WORLD_FLUID,
        Capability.WORLD_FLUID_ELLIPSOID,
        Capability.COLLISION_EXPLICIT_PAIRS,
    }
    Options: ClassVar[type[BackendOptions]] = MujocoWarpOptions
    options: MujocoWarpOptions

    @classmethod
    def engine_label(cls) -> str:
        return f"MuJoCo Warp {cls.engine_version()} (MuJoCo {mujoco.mj_versionString()})"

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        super().check_world(world, options)
        if isinstance(options, MujocoWarpOptions) and options.device != "cpu":
            _check_cuda(options.device)

    def _build(self) -> None:
        super()._build()
        wp = _quiet_warp()
        import mujoco_warp as mjw

        self._mjw = mjw
        self._device = wp.get_device(self.options.device)
        m = self._m
        nconmax = self.options.contacts_per_body * len(self.world.bodies) + 8
        njmax = ROWS_PER_CONTACT * nconmax + ROWS_PER_DOF * m.nv + 8
        self._nconmax = nconmax
        self._messages: list[str] = []
        # the MuJoCo adapter turns MuJoCo's auto-reset off so that a blow-up is reported, not hidden; MJWarp
        # has no auto-reset at all (the runner finds blow-ups on every engine)
        m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
        try:
            with wp.ScopedDevice(self._device), contextlib.redirect_stdout(io.StringIO()) as out:
                self._wm = mjw.put_model(m)
                self._wd = mjw.put_data(m, self._d, nworld=1, nconmax=nconmax, njmax=njmax)
        except NotImplementedError as exc:  # MJWarp's own refusal of a model feature (its feature-parity list)
            raise UnsupportedFeature(f"mujoco_warp: MJWarp cannot run this world: {exc}") from None
        self._keep(out)
        box_box_as_mujoco(self._wm)
        self._frictionloss = self._wm.tendon_frictionloss
        self._wm.opt.tolerance.fill_(_solver_tolerance(m, self._d))
        self._controls_changed = False

    def _keep(self, out: io.StringIO) -> None:
        """Keep what MJWarp printed (its overflow warnings), not Warp's kernel compile/cache lines: those differ
        between a first run and a cached one, and the trace must not."""
        self._messages += [
            line for line in out.getvalue().splitlines() if line.strip() and not _WARP_MODULE_LINE.match(line)
        ]

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        super()._set_motor(joint, vel, fmax)
        if hasattr(self, "_wm"):  # the build's own first motors are copied with the model
            slot = int(self._motor_of[joint])
            values = self._frictionloss.numpy()
            values.reshape(-1)[self._motor_tendon[slot]] = fmax
            self._frictionloss.assign(values)

    def _set_control(self, actuator: int, ctrl: float) -> None:
        """The host ``ctrl`` (the MuJoCo adapter's), copied to the device before the next engine step."""
        if 0 <= actuator < self._m.nu and self._d.ctrl[actuator] == ctrl:
            return  # the runner sets every driven actuator's ctrl before every step, mostly unchanged
        super()._set_control(actuator, ctrl)
        self._controls_changed = True

    def _engine_step(self, native: bool, friction: float | None) -> None:
        d, wd = self._d, self._wd
        wd.qpos.assign(d.qpos.reshape(1, -1))
        wd.qvel.assign(d.qvel.reshape(1, -1))
        wd.xfrc_applied.assign(d.xfrc_applied.reshape(1, -1, 6))
        if self._controls_changed:  # held on the device until changed, as MjData's
            wd.ctrl.assign(d.ctrl.reshape(1, -1))
            self._controls_changed = False
        with contextlib.redirect_stdout(io.StringIO()) as out:
            if native:  # the model file's own options: MuJoCo's own step, as the mujoco backend takes it
                self._mjw.step(self._wm, wd)
            else:
                rules = [_corrections.WorldRules(friction, self._impacts)]
                _corrections.step(self._mjw, self._wm, wd, rules, self._h, float(self._m.opt.impratio))
        self._keep(out)
        d.qpos[:] = wd.qpos.numpy()[0]
        d.qvel[:] = wd.qvel.numpy()[0]
        d.time = float(wd.time.numpy()[0])
        if int(wd.nacon.numpy()[0]) >= self._nconmax:
            raise EngineFailure(
                f"mujoco_warp: the contact buffer ({self._nconmax} contacts) filled up by t="
                f"{(self.steps + 1) * self.world.dt:g} s, so contacts were dropped; raise "
                "backend_options.mujoco_warp.contacts_per_body",
                backend=self.name,
                time=(self.steps + 1) * self.world.dt,
            )

    def _constraint_forces(self) -> np.ndarray:
        return np.asarray(self._wd.qfrc_constraint.numpy()[0], dtype=np.float64)

    def _reactions_now(self) -> np.ndarray:
        """The MuJoCo adapter's reading (``MujocoBackend._reactions_now``) from MJWarp's own
        ``rne_postconstraint`` on the device data: the host MjData has no accelerations or constraint forces."""
        wd = self._wd
        self._mjw.rne_postconstraint(self._wm, wd)
        child, sign, first = self._reaction
        wrench = wd.cfrc_int.numpy()[0][child].astype(np.float64)
        subtree_com = wd.subtree_com.numpy()[0].astype(np.float64)
        xipos = wd.xipos.numpy()[0].astype(np.float64)
        force = sign[:, None] * wrench[:, 3:]
        origin = sign[:, None] * (wrench[:, :3] + np.cross(subtree_com[self._m.body_rootid[child]], wrench[:, 3:]))
        torque = origin - np.cross(xipos[first], force)
        return np.hstack((force, torque)).ravel()

    def _check(self) -> None:
        """MJWarp keeps no warnings; blow-ups are the runner's to find (runner.sim.session)."""

    def _touching(self) -> list[Contact]:
        wd = self._wd
        n = int(wd.nacon.numpy()[0])
        if n == 0:
            return []
        c = wd.contact
        dist = c.dist.numpy()[:n].astype(np.float64)
        geom = c.geom.numpy()[:n]
        rows = c.efc_address.numpy()[:n, 0]
        keep = dist <= 0.0
        dist, geom, rows = dist[keep], geom[keep], rows[keep]
        efc = wd.efc.force.numpy()[0]
        force = np.where(rows >= 0, efc[np.maximum(rows, 0)], 0.0).astype(np.float64)
        owner = self._geom_body
        return group_by_pair(len(self.world.bodies), owner[geom[:, 0]], owner[geom[:, 1]], -dist, force)

    def _contact_points(self) -> list[ContactPoint]:
        """MJWarp's contacts of the last engine step (distance <= 0), read as the MuJoCo adapter reads MjData's:
        ``pos``, the normal ``frame[0]`` and the normal force (``mujoco_warp.contact_force``, which decodes a
        model file's pyramidal cone as ``mj_contactForce`` does)."""
        wd = self._wd
        n = int(wd.nacon.numpy()[0]) if self.steps else 0
        if n == 0:
            return []
        c = wd.contact
        dist = c.dist.numpy()[:n].astype(np.float64)
        keep = np.flatnonzero(dist <= 0.0)
        if keep.size == 0:
            return []
        wp = _quiet_warp()
        ids = wp.array(keep.astype(np.int32), dtype=wp.int32, device=self._device)
        wrench = wp.zeros(keep.size, dtype=wp.spatial_vector, device=self._device)
        self._mjw.contact_force(self._wm, wd, ids, False, wrench)
        force = wrench.numpy()[:, 0].astype(np.float64)
        geom = c.geom.numpy()[keep]
        pos = c.pos.numpy()[keep].astype(np.float64)
        normal = c.frame.numpy()[keep, 0, :].astype(np.float64)
        owner = self._geom_body
        columns = zip(owner[geom[:, 0]].tolist(), owner[geom[:, 1]].tolist(), pos.tolist(), normal.tolist(),
                      (-dist[keep]).tolist(), force.tolist(), strict=True)  # fmt: skip
        return sorted_points([contact_point(*column) for column in columns])

    def _drain_messages(self) -> list[str]:
        out, self._messages = self._messages, []
        return out

    def _settings(self) -> dict[str, Any]:
        s = super()._settings()
        own = "mujoco_warp.step1, fwd_actuation, fwd_acceleration, the solve (again for the Coulomb correction), "
        own += "implicit: the MuJoCo adapter's step"
        s.update(
            engine=f"mujoco_warp {self.engine_version()} (mujoco {mujoco.__version__}, warp {self._warp_version()})",
            device=str(self._device),
            step="mujoco_warp.step" if self.world.model_options else own,
            contact_buffer=self._nconmax,
        )
        return s

    @staticmethod
    def _warp_version() -> str:
        import warp as wp

        return str(wp.config.version)
