"""One world of a :class:`~backends.mujoco_warp._batch.MujocoWarpBatch`: the mujoco_warp backend's contract.

A view is the single-world adapter (``MujocoWarpBackend``) without a device model of its own: it keeps its world's
MuJoCo model and host ``MjData`` (built exactly as the single-world adapter builds them), its inputs and every
read of the MuJoCo adapter. Its engine steps are taken by the batch: ``step_all`` runs, for every world, the
MuJoCo adapter's step around one batched engine step (``_corrections.step``) per engine step (``begin`` /
``before`` / ``after`` / ``end`` below are that step's parts, in its order), and the view's ``step()`` only
consumes it.

A world with nothing to do on the host during a step (no forces, motors, kinematic bodies, watched joints, resets
or substeps: a box drop) is "idle": its host ``MjData`` is filled from the batch's copies only when it is read.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from .._kit import KinematicPose, contact_point, group_by_pair, sorted_points
from ..errors import EngineFailure
from ..mujoco._backend import MujocoBackend
from ..types import BodyStates, CompiledWorld, Contact, ContactPoint, ImportedModel, JointStates, Quat, Vec3
from . import _corrections
from ._backend import ROWS_PER_CONTACT, ROWS_PER_DOF, MujocoWarpBackend, _quiet_warp

if TYPE_CHECKING:
    from ._batch import MujocoWarpBatch


class WorldView(MujocoWarpBackend):
    """World ``index`` of ``batch`` (``batch`` None: a world built only to be compared, never stepped)."""

    def __init__(self, world: CompiledWorld, batch: MujocoWarpBatch | None, index: int) -> None:
        self._batch = batch
        self._index = index
        self._failure: EngineFailure | None = None  # what this world met in the last step_all
        self._stepped = False  # step_all advanced this world since its last step()
        self._seen = 0  # the batch's engine step the host MjData holds
        self._dirty = False  # an input wrote the host state since the last step
        super().__init__(world)

    def _build(self) -> None:
        """The single-world adapter's build without its device copy (the batch holds one for all worlds)."""
        MujocoBackend._build(self)
        wp = _quiet_warp()
        self._device = wp.get_device(self.options.device)
        m = self._m
        self._nconmax = self.options.contacts_per_body * len(self.world.bodies) + 8
        self._njmax = ROWS_PER_CONTACT * self._nconmax + ROWS_PER_DOF * m.nv + 8
        self._messages: list[str] = []
        m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)

    def attach(self, batch: MujocoWarpBatch) -> None:
        """Become world ``index`` of ``batch`` (a view built by ``why_not``, before any step)."""
        self._batch = batch

    # --- what the batch compares and copies -----------------------------------------------------------

    @property
    def index(self) -> int:
        return self._index

    @property
    def model(self) -> mujoco.MjModel:
        return self._m

    @property
    def data(self) -> mujoco.MjData:
        return self._d

    @property
    def nconmax(self) -> int:
        return self._nconmax

    @property
    def njmax(self) -> int:
        return self._njmax

    @property
    def rules(self) -> _corrections.WorldRules:
        """The MuJoCo adapter's corrections of this world's engine steps (its surfaces' damping and bounces)."""
        return _corrections.WorldRules(self._layout.friction_damping, self._impacts)

    @property
    def engine_h(self) -> float:
        """The engine step (s)."""
        return self._h

    @property
    def engine_steps(self) -> int:
        """MuJoCo steps per scenario step."""
        return self._nsteps

    # --- the batch's step, in the MuJoCo adapter's order (backends/mujoco/_backend.py, _step) ----------

    def busy(self) -> bool:
        """Whether this step needs the world's host work (otherwise its host state is filled when read)."""
        return bool(
            self._dirty or self.forces or self.kinematic or self._helper_dof.size or self.world.reaction_joints
            or self._nsteps > 1
        )  # fmt: skip

    def begin(self) -> None:
        self.sync()
        d = self._d
        for i, acc in self.forces.items():  # held for every engine step of this step, then cleared
            d.xfrc_applied[self._layout.body_id[i]] = acc
        if self._helper_dof.size:
            self._motor_mean.start()
        if self.world.reaction_joints:
            self._reaction_mean.start()
        self._substep_contacts.start()

    def before(self, k: int) -> None:
        if k:
            for i, pose in self.kinematic.items():
                self._put(i, pose, self._times[k - 1])
        if self._helper_dof.size:
            self._d.qvel[self._helper_dof] = self._target

    def after(self, k: int) -> None:
        if self._helper_dof.size:
            self._motor_mean.add(-self._constraint_forces()[self._helper_dof])  # the helper feels -(motor force)
        if self.world.reaction_joints:
            self._reaction_mean.add(self._reactions_now())
        if k + 1 < self._nsteps:
            self._substep_contacts.add(self._touching())

    def end(self) -> None:
        if self._helper_dof.size:
            self._motor_mean.finish()
        if self.world.reaction_joints:
            self._reaction_mean.finish()
        self._d.xfrc_applied[:] = 0.0
        dt = self.world.dt
        for i, pose in self.kinematic.items():  # now exactly where the velocity says, as the next step begins
            pos, quat = pose.at(dt)
            self._put(i, KinematicPose(pos, quat, pose.lin_vel, pose.ang_vel), 0.0)
        self._listed = None
        self._stale = True
        self._dirty = False

    def stepped(self, failure: EngineFailure | None) -> None:
        self._stepped = True
        if failure is not None and self._failure is None:
            self._failure = failure

    def sync(self) -> None:
        """Fill the host MjData with this world's state after the batch's last engine step."""
        batch = self._batch
        if batch is None or self._seen == batch.engine_step_count:
            return
        i, d = self._index, self._d
        d.qpos[:] = batch.qpos[i]
        d.qvel[:] = batch.qvel[i]
        d.time = float(batch.time[i])
        self._seen = batch.engine_step_count
        self._listed = None
        self._stale = True

    def add_messages(self, lines: list[str]) -> None:
        self._messages += lines

    def take_failure(self) -> EngineFailure | None:
        failure, self._failure = self._failure, None
        return failure

    # --- the contract's hooks ---------------------------------------------------------------------------

    def _step(self) -> None:
        if not self._stepped:
            raise RuntimeError(f"mujoco_warp batch: world {self._index} was not stepped by step_all since its step()")
        self._stepped = False
        failure = self.take_failure()
        if failure is not None:
            raise failure

    def _engine_step(self, native: bool, friction: float | None) -> None:
        raise RuntimeError("a world of a batch is stepped by MujocoWarpBatch.step_all")

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        super()._set_motor(joint, vel, fmax)  # the host model's row; the batch copies the rows of all worlds
        if self._batch is not None:
            self._batch.motors_changed()

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self.sync()
        super()._reset_body(body, pos, quat, lin_vel, ang_vel)
        self._dirty = True

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self.sync()
        super()._place_kinematic(body, pose)
        self._dirty = True

    def _set_control(self, actuator: int, ctrl: float) -> None:
        """The host ``ctrl``; the batch copies every world's row before its next engine step (no host work:
        the world may stay idle)."""
        if 0 <= actuator < self._m.nu and self._d.ctrl[actuator] == ctrl:
            return
        MujocoBackend._set_control(self, actuator, ctrl)
        if self._batch is not None:
            self._batch.controls_changed()

    def _constraint_forces(self) -> np.ndarray:
        assert self._batch is not None  # noqa: S101 - stepped only by a batch
        return self._batch.constraint_forces(self._index)

    def _touching(self) -> list[Contact]:
        assert self._batch is not None  # noqa: S101 - stepped only by a batch
        dist, geom, rows, efc = self._batch.contacts_of(self._index)
        if dist.size == 0:
            return []
        keep = dist <= 0.0
        dist, geom, rows = dist[keep], geom[keep], rows[keep]
        force = np.where(rows >= 0, efc[np.maximum(rows, 0)], 0.0).astype(np.float64)
        owner = self._geom_body
        return group_by_pair(len(self.world.bodies), owner[geom[:, 0]], owner[geom[:, 1]], -dist, force)

    def _reactions_now(self) -> np.ndarray:
        """The single adapter's reading, from this world's rows of the batch's device data."""
        assert self._batch is not None  # noqa: S101 - stepped only by a batch
        wrench, subtree_com, xipos = self._batch.reaction_rows(self._index)
        child, sign, first = self._reaction
        wrench = wrench[child]
        force = sign[:, None] * wrench[:, 3:]
        origin = sign[:, None] * (wrench[:, :3] + np.cross(subtree_com[self._m.body_rootid[child]], wrench[:, 3:]))
        torque = origin - np.cross(xipos[first], force)
        return np.hstack((force, torque)).ravel()

    def _contact_points(self) -> list[ContactPoint]:
        if self._batch is None or not self.steps:
            return []
        geom, pos, normal, dist, force = self._batch.contact_points_of(self._index)
        owner = self._geom_body
        columns = zip(owner[geom[:, 0]].tolist(), owner[geom[:, 1]].tolist(), pos.tolist(), normal.tolist(),
                      (-dist).tolist(), force.tolist(), strict=True)  # fmt: skip
        return sorted_points([contact_point(*column) for column in columns])

    def _body_states(self) -> BodyStates:
        self.sync()
        return super()._body_states()

    def _joint_states(self) -> JointStates:
        self.sync()
        return super()._joint_states()

    def _contacts(self) -> list[Contact]:
        self.sync()
        return super()._contacts()

    def _imported_model(self) -> ImportedModel:
        self.sync()
        return super()._imported_model()

    def _close(self) -> None:
        self._batch = None
