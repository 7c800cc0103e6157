"""The MuJoCo adapter: inputs, stepping and fresh reads on the model that ``_model.build`` compiles."""

from __future__ import annotations

from typing import Any, ClassVar

import mujoco
import numpy as np

from .._kit import (
    BackendOptions,
    KinematicPose,
    SubstepContacts,
    SubstepMean,
    substep_times,
)
from .._kit.stacks import stack_height
from ..base import Backend
from ..errors import EngineFailure
from ..geometry import quat_conj, quat_rotate
from ..types import (
    MODEL_FILE_CAPABILITIES,
    RIGID_BODY_CAPABILITIES,
    ROBOT_CAPABILITIES,
    BodyStates,
    Capability,
    CompiledWorld,
    Contact,
    ContactPoint,
    ImportedModel,
    JointKind,
    JointStates,
    Motion,
    Precision,
    Quat,
    Vec3,
)
from . import _coulomb, _native
from ._bounce import impacts_of
from ._imported import read_imported
from ._model import build, plan_tree
from ._native import set_start
from ._options import MujocoOptions, check_stack, engine_substeps
from ._reads import check_reactions, contact_points, reaction_rows, reactions_now, touching
from ._settings import engine_settings


def _no_log_file() -> None:
    """MuJoCo appends its warnings to MUJOCO_LOG.TXT in the working directory (a process-wide setting).

    The adapter turns the warnings that matter into EngineFailure; the console copy stays.
    """
    if hasattr(mujoco, "MjLogConfig"):  # MuJoCo 4
        config = mujoco.MjLogConfig.get()
        config.logto_file = False
        config.set()


_no_log_file()
#: MuJoCo's own verdicts on its state: positions, velocities or accelerations it calls invalid (NaN or
#: beyond mjMAXVAL). With auto-reset disabled it only counts them; the adapter reports them.
_BAD_STATE = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL, mujoco.mjtWarning.mjWARN_BADQACC)
_BAD = slice(int(_BAD_STATE[0]), int(_BAD_STATE[-1]) + 1)  # their counters in MjData.warning.number
_RATED = (JointKind.SLIDER, JointKind.HINGE)
_YZX, _ZXY = np.array([1, 2, 0]), np.array([2, 0, 1])  # cross(a, r) = a[YZX]*r[ZXY] - a[ZXY]*r[YZX]


class MujocoBackend(Backend):
    """MuJoCo through MjSpec, stepped with ODE semantics (docs/backends/mujoco.md)."""

    name: ClassVar[str] = "mujoco"
    engine_distribution: ClassVar[str] = "mujoco"
    precision: ClassVar[Precision] = Precision.FLOAT64  # mjtNum is double
    #: no shape:trimesh: MuJoCo collides with a mesh's convex hull only (docs/backends/mujoco.md); what only
    #: an engine building a robot from its file runs: MJCF robots are built from their file (_native)
    capabilities: ClassVar[frozenset[Capability]] = (
        RIGID_BODY_CAPABILITIES
        | (ROBOT_CAPABILITIES - {Capability.SHAPE_TRIMESH})
        | MODEL_FILE_CAPABILITIES
        | {Capability.JOINT_ARMATURE, Capability.CONTACT_POINTS}  # dof_armature
        | {Capability.JOINT_REACTION}  # cfrc_int (mj_rnePostConstraint)
        | {Capability.JOINT_MIMIC}  # a joint equality (_model._add_mimics)
    )
    Options: ClassVar[type[BackendOptions]] = MujocoOptions
    #: mju_error and the bindings' own failures; MjSpec.compile's ValueError is translated where it is called.
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = (mujoco.FatalError, mujoco.UnexpectedError)
    options: MujocoOptions

    @classmethod
    def engine_label(cls) -> str:
        engine, wrapper = mujoco.mj_versionString(), cls.engine_version()
        return f"MuJoCo {engine}" + ("" if wrapper == engine else f" (mujoco {wrapper})")

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        if isinstance(options, MujocoOptions) and options.engine_substeps is None:
            check_stack(stack_height(world))  # set by hand, the column is the scenario's to judge
        plan_tree(world, _native.load(world))  # a kinematic loop, one MJCF robot at most, ... (no model built)
        check_reactions(world)

    def _build(self) -> None:
        world = self.world
        self._stack = stack_height(world)  # the registry refused a column too tall first (check_world)
        self._nsteps = world.substeps * engine_substeps(self.options, world.dt / world.substeps, self._stack)
        if world.model_options:  # the model's own timestep (checked equal to dt / substeps when loaded)
            self._nsteps = world.substeps
        self._h = world.dt / self._nsteps
        self._times = substep_times(world.dt, self._nsteps)
        self._layout = build(world, self.options, self._h)
        self._m = self._layout.model
        self._d = mujoco.MjData(self._m)
        m, lay = self._m, self._layout
        self._impacts = impacts_of(world, m, self._h, self.options)
        ids = lay.body_id
        self._root = m.body_rootid[ids]
        self._free = {  # world index -> (qpos address, dof address) of free bodies (dynamic or kinematic)
            i: (int(m.jnt_qposadr[m.body_jntadr[b]]), int(m.jnt_dofadr[m.body_jntadr[b]]))
            for i, b in enumerate(ids)
            if m.body_jntnum[b] == 1 and m.jnt_type[m.body_jntadr[b]] == mujoco.mjtJoint.mjJNT_FREE
        }
        self._sign = np.ones(len(world.joints))  # world joint coordinate = sign * MuJoCo's
        for edge in lay.edges.values():
            if edge.joint is not None:
                self._sign[edge.joint] = edge.sign
        motors = np.flatnonzero(lay.motor_id >= 0)
        # slots: the motors in tendon order (an MJCF file's own tendons may come first)
        order = np.argsort(lay.motor_id[motors])
        self._motor_tendon = lay.motor_id[motors][order]  # slot -> the motor's tendon id
        self._motor_of = np.full(len(world.joints), -1)  # world joint -> slot
        self._motor_of[motors[order]] = np.arange(motors.size)
        self._helper_dof = lay.helper_dof[motors][order]
        self._target = np.zeros(motors.size)  # per slot, in the MuJoCo joint's coordinate
        #: per joint tuple ``set_motors`` was given: its motors' tendons, slots and signs
        self._motor_rows: dict[tuple[int, ...], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        #: the last ``_set_motors`` call's joints and force bounds, while no other call has written any since (a
        #: servo's bounds do not change between steps: the same values are not written again)
        self._bounds_written: tuple[tuple[int, ...], list[float]] | None = None
        self._motor_mean = SubstepMean(motors.size)
        self._reaction = reaction_rows(world, m, lay)  # (child body, sign, first body) per watched joint
        self._reaction_mean = SubstepMean(6 * len(world.reaction_joints))
        self._substep_contacts = SubstepContacts(self._nsteps)  # the step's engine steps but the last
        self._listed: list[Contact] | None = []  # None: the last engine step's contacts are still in MjData
        self._warnings = self._d.warning.number  # live views into MjData
        self._bad_counts = self._warnings[_BAD]  # the invalid-state warnings' counters (a view too)
        self._qpos, self._qvel = self._d.qpos, self._d.qvel
        self._geom_body = lay.geom_body  # MuJoCo geom -> world body, for _touching
        rated = np.array([j for j, joint in enumerate(world.joints) if joint.kind in _RATED], dtype=np.int64)
        self._rated = rated  # the joints with a coordinate: slider, hinge
        self._rated_qpos, self._rated_dof = m.jnt_qposadr[lay.joint_id[rated]], m.jnt_dofadr[lay.joint_id[rated]]
        self._rated_sign = self._sign[rated]
        #: what a joint without a coordinate reads (NaN) or a joint without a motor feels (0), copied per read
        self._no_reading, self._no_force = np.full(len(world.joints), np.nan), np.zeros(len(world.joints))
        self._motored = motors  # world joints with a motor, their slots, signs
        self._motored_slot, self._motored_sign = self._motor_of[motors], self._sign[motors]
        every = np.arange(len(world.joints))
        #: every joint rated, or motored, in world order (a robot's, usually): its reading is the whole array
        self._all_rated = rated.size == every.size and bool((rated == every).all())
        self._all_motored = np.size(motors) == every.size and bool((np.asarray(motors) == every).all())
        self._stale = True
        # a reading counts from the start, itself from the file's zero: qpos0, a joint's `ref` (0 for the
        # runner's own joints), so world = sign (qpos - qpos0) - start (an MJCF robot's start: _native)
        starts = set_start(m, self._d, world, lay.joint_id)[rated]
        self._starts = starts + self._rated_sign * m.qpos0[self._rated_qpos]
        for i, body in enumerate(world.bodies):
            if body.motion is Motion.DYNAMIC:
                self._set_velocity(i, body.lin_vel, body.ang_vel)
        self._initial_joint_rates()
        for j, joint in enumerate(world.joints):
            if self._motor_of[j] >= 0:
                motor = joint.motor
                self._set_motor(j, motor.vel if motor else 0.0, motor.fmax if motor else 0.0)
        for i, pose in self.kinematic.items():
            self._put(i, pose, 0.0)

    # --- inputs ---------------------------------------------------------------------------------

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self._put(body, pose, 0.0)

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        slot = int(self._motor_of[joint])
        self._m.tendon_frictionloss[self._motor_tendon[slot]] = fmax  # 0: no row, the motor is off
        self._bounds_written = None
        self._target[slot] = self._sign[joint] * vel

    def _set_motors(self, joints: tuple[int, ...], vels: list[float], fmaxes: list[float]) -> None:
        """The same writes as ``_set_motor``, one array assignment each for all the joints (a subclass that adds
        to ``_set_motor``, MuJoCo Warp's, gets one call of it per joint)."""
        if type(self)._set_motor is not MujocoBackend._set_motor:
            super()._set_motors(joints, vels, fmaxes)
            return
        rows = self._motor_rows.get(joints)
        if rows is None:
            slots = self._motor_of[list(joints)].astype(int)
            rows = self._motor_rows[joints] = (self._motor_tendon[slots], slots, self._sign[list(joints)])
        tendons, slots, sign = rows
        if self._bounds_written is None or self._bounds_written[0] != joints or self._bounds_written[1] != fmaxes:
            self._m.tendon_frictionloss[tendons] = fmaxes  # 0: no row, the motor is off
            self._bounds_written = joints, fmaxes
        self._target[slots] = sign * np.array(vels)

    def _set_control(self, actuator: int, ctrl: float) -> None:
        """The MJCF file's actuator, in the file's order (the scenario's own parts add no actuator): MuJoCo
        clamps ``ctrl`` to its ctrlrange and computes the force itself, as the file runs."""
        if not 0 <= actuator < self._m.nu:
            self._refuse(f"set_control: the model has {self._m.nu} actuators, not {actuator + 1}")
        self._d.ctrl[actuator] = ctrl

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        qadr, _ = self._free[body]
        self._d.qpos[qadr : qadr + 3] = pos
        self._d.qpos[qadr + 3 : qadr + 7] = quat
        self._set_velocity(body, lin_vel, ang_vel)
        self._stale = True

    # --- stepping -------------------------------------------------------------------------------

    def _step(self) -> None:
        d, nsteps, motors = self._d, self._nsteps, self._helper_dof.size > 0
        native = self.world.model_options  # MuJoCo's own step, as the model file runs
        friction = self._layout.friction_damping
        forced = bool(self.forces)
        if forced:  # held for every engine step of this step, then cleared
            for i, acc in self.forces.items():
                d.xfrc_applied[self._layout.body_id[i]] = acc
        if motors:
            self._motor_mean.start()
        watched = bool(self.world.reaction_joints)
        if watched:
            self._reaction_mean.start()
        self._substep_contacts.start()
        for k in range(nsteps):
            if k:
                for i, pose in self.kinematic.items():
                    self._put(i, pose, self._times[k - 1])
            if motors:
                d.qvel[self._helper_dof] = self._target
            self._engine_step(native, friction)
            if motors:
                self._motor_mean.add(-self._constraint_forces()[self._helper_dof])  # the helper feels -(motor force)
            if watched:
                self._reaction_mean.add(self._reactions_now())
            if k + 1 < nsteps:  # the last engine step's contacts stay in MjData until contacts() asks
                self._substep_contacts.add(self._touching())
        if motors:
            self._motor_mean.finish()
        if watched:
            self._reaction_mean.finish()
        if forced:
            d.xfrc_applied[:] = 0.0
        dt = self.world.dt
        for i, pose in self.kinematic.items():  # now exactly where the velocity says, as the next step begins
            pos, quat = pose.at(dt)
            self._put(i, KinematicPose(pos, quat, pose.lin_vel, pose.ang_vel), 0.0)
        self._listed = None  # contacts() groups the last engine step's contacts when first asked
        self._stale = True
        self._check()

    def _engine_step(self, native: bool, friction: float | None) -> None:
        """One engine step of ``self._h`` on MjData (MJWarp's adapter steps its device copy instead)."""
        if native:
            mujoco.mj_step(self._m, self._d)
        else:
            _coulomb.step(self._m, self._d, friction, self._impacts)

    def _constraint_forces(self) -> np.ndarray:
        """The last engine step's constraint forces per dof (``qfrc_constraint``)."""
        return self._d.qfrc_constraint

    def _reactions_now(self) -> np.ndarray:
        """The watched joints' wrenches on their first bodies in the engine step just taken, flattened.

        ``mj_rnePostConstraint`` gives ``cfrc_int``: the wrench (torque, force) a body's parent applies to it
        through its joint, at the subtree centre of mass of its tree's root, world axes, from the step's
        accelerations and the kinematics the step was computed with (still in MjData after it). Moved to the
        world origin, turned to the first body (the opposite wrench where the tree hangs the joint from the
        other end) and moved to that body's centre of mass (``_reads.reactions_now``)."""
        return reactions_now(self._m, self._d, self._reaction)

    def _joint_reactions(self) -> np.ndarray:
        return self._reaction_mean.mean.reshape(-1, 6).copy()

    def _put(self, body: int, pose: KinematicPose, t: float) -> None:
        """Impose a kinematic body's pose ``t`` into the step, and its velocity."""
        qadr, _ = self._free[body]
        pos, q = pose.at(t)
        self._d.qpos[qadr : qadr + 3] = pos
        self._d.qpos[qadr + 3 : qadr + 7] = q
        self._set_velocity(body, pose.lin_vel, pose.ang_vel, q)
        self._stale = True

    def _set_velocity(self, body: int, lin: Vec3, ang: Vec3, quat: Quat | None = None) -> None:
        """Free joints take the linear velocity in the world frame, the angular one in the body frame."""
        if body not in self._free:
            return  # jointed bodies: see _initial_joint_rates
        qadr, dadr = self._free[body]
        q = quat if quat is not None else tuple(self._d.qpos[qadr + 3 : qadr + 7])
        self._d.qvel[dadr : dadr + 3] = lin
        self._d.qvel[dadr + 3 : dadr + 6] = quat_rotate(quat_conj(q), ang)

    def _initial_joint_rates(self) -> None:
        """A jointed body's initial velocity relative to its parent's, projected on its joint."""
        m, world = self._m, self.world
        for name, edge in self._layout.edges.items():
            if edge.joint is None or self._layout.joint_id[edge.joint] < 0:
                continue
            child = world.bodies[world.body_index(name)]
            parent = world.bodies[world.body_index(edge.parent)] if edge.parent is not None else None
            lin = np.subtract(child.lin_vel, parent.lin_vel if parent else (0.0, 0.0, 0.0))
            ang = np.subtract(child.ang_vel, parent.ang_vel if parent else (0.0, 0.0, 0.0))
            joint = world.joints[edge.joint]
            dof = m.jnt_dofadr[self._layout.joint_id[edge.joint]]
            if joint.kind is JointKind.SLIDER:
                self._d.qvel[dof] = float(np.dot(lin, joint.axis))
            elif joint.kind is JointKind.HINGE:
                self._d.qvel[dof] = float(np.dot(ang, joint.axis))
            else:  # ball: the rate in the child's frame
                self._d.qvel[dof : dof + 3] = quat_rotate(quat_conj(child.quat), ang)

    def _check(self) -> None:
        """MuJoCo's own verdict: a state it counted as invalid (its warnings) is an EngineFailure. Blow-ups it
        does not call invalid are the runner's to find (runner.sim.session)."""
        if not any(self._bad_counts.tolist()):  # a few ints: cheaper as a list than as a numpy reduction
            return
        d = self._d
        dofs = {d.warning[w].lastinfo for w in _BAD_STATE[1:] if d.warning[w].number}  # lastinfo: the dof
        bad_bodies = {self._m.dof_bodyid[i] for i in dofs if 0 <= i < self._m.nv}
        named = [b.name for b, mj in zip(self.world.bodies, self._layout.body_id, strict=True) if mj in bad_bodies]
        body = named[0] if named else None
        time = (self.steps + 1) * self.world.dt
        raise EngineFailure(
            f"mujoco: the engine reported an invalid state (NaN, inf or a huge value in qpos, qvel or qacc) "
            f"by t={time:g} s",
            backend=self.name,
            body=body,
            time=time,
        )

    # --- contacts -------------------------------------------------------------------------------

    def _touching(self) -> list[Contact]:
        """Body pairs touching (distance <= 0) in the last engine step (MjData keeps them until the next)."""
        return touching(self._d, self._geom_body, len(self.world.bodies))

    def _contact_points(self) -> list[ContactPoint]:
        """MjData's contacts of the last engine step (distance <= 0): ``_reads.contact_points``."""
        return contact_points(self._m, self._d, self._geom_body, bool(self.steps))

    def _contacts(self) -> list[Contact]:
        if self._listed is None:  # first call since the step: group the last engine step's contacts now
            self._listed = self._substep_contacts.merged(self._touching())
        return self._listed.copy()

    # --- reads ----------------------------------------------------------------------------------

    def _refresh(self) -> None:
        """Recompute poses and velocities from qpos/qvel (mj_step leaves xpos/xquat one step behind)."""
        if self._stale:
            mujoco.mj_kinematics(self._m, self._d)
            mujoco.mj_comPos(self._m, self._d)
            mujoco.mj_comVel(self._m, self._d)
            self._stale = False

    def _body_states(self) -> BodyStates:
        self._refresh()
        d, ids = self._d, self._layout.body_id
        pos = d.xpos[ids]
        ang = d.cvel[ids, :3]
        r = pos - d.subtree_com[self._root]  # cvel is about the root's COM; np.cross's products, in its order:
        lin = d.cvel[ids, 3:] + (ang[:, _YZX] * r[:, _ZXY] - ang[:, _ZXY] * r[:, _YZX])
        return BodyStates(pos=pos, quat=d.xquat[ids], lin_vel=lin, ang_vel=ang)

    def _joint_states(self) -> JointStates:
        rated, motored = self._rated, self._motored
        if self._all_rated and self._all_motored:  # the same values, without the copies and the indexed writes
            sign = self._rated_sign
            return JointStates(position=sign * self._qpos[self._rated_qpos] - self._starts,
                               velocity=sign * self._qvel[self._rated_dof],
                               motor_force=self._motored_sign * self._motor_mean.mean[self._motored_slot])  # fmt: skip
        position, velocity, force = self._no_reading.copy(), self._no_reading.copy(), self._no_force.copy()
        if rated.size:
            sign = self._rated_sign
            position[rated] = sign * self._qpos[self._rated_qpos] - self._starts
            velocity[rated] = sign * self._qvel[self._rated_dof]
        if motored.size:
            force[motored] = self._motored_sign * self._motor_mean.mean[self._motored_slot]
        return JointStates(position=position, velocity=velocity, motor_force=force)

    def _imported_model(self) -> ImportedModel:
        starts = np.zeros(len(self.world.joints))
        starts[self._rated] = self._starts
        return read_imported(self._m, self._d, self.world, self._layout, self._sign, starts)

    def _settings(self) -> dict[str, Any]:
        return engine_settings(
            self._m, self.options, bool(self.world.model_options), self._h, self._nsteps, self._stack
        )
