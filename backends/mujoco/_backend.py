"""The MuJoCo adapter: inputs, stepping and fresh reads on the model that ``_model.build`` compiles."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import mujoco
import numpy as np

from ..base import Backend
from ..errors import EngineFailure, UnsupportedFeature, map_engine_errors
from ..geometry import integrate_quat, quat_conj, quat_rotate
from ..types import (
    RIGID_BODY_CAPABILITIES,
    BodyStates,
    Capability,
    CompiledWorld,
    Contact,
    JointKind,
    JointStates,
    Motion,
    Quat,
    Vec3,
    new_contact,
)
from . import _coulomb
from ._model import IMPEDANCE, KINEMATIC_MASS_RATIO, MU_MAX, Options, build


def _no_log_file() -> None:
    """MuJoCo appends its warnings to MUJOCO_LOG.TXT in the working directory (a process-wide setting).

    The adapter turns the warnings that matter into EngineFailure; the console copy stays.
    """
    if hasattr(mujoco, "MjLogConfig"):  # MuJoCo 4
        config = mujoco.MjLogConfig.get()
        config.logto_file = False
        config.set()


_no_log_file()
_Pairs = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # pair code a*N+b, points, depth, force
_NO_PAIRS: _Pairs = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), np.zeros(0))
_BAD_STATE = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL, mujoco.mjtWarning.mjWARN_BADQACC)
_BAD = slice(int(_BAD_STATE[0]), int(_BAD_STATE[-1]) + 1)  # their counters in MjData.warning.number
_RATED = (JointKind.SLIDER, JointKind.HINGE)
_YZX, _ZXY = np.array([1, 2, 0]), np.array([2, 0, 1])  # cross(a, r) = a[YZX]*r[ZXY] - a[ZXY]*r[YZX]


class MujocoBackend(Backend):
    """MuJoCo through MjSpec, stepped with ODE semantics (docs/backends/mujoco.md)."""

    name: ClassVar[str] = "mujoco"
    engine_distribution: ClassVar[str] = "mujoco"
    capabilities: ClassVar[frozenset[Capability]] = RIGID_BODY_CAPABILITIES
    option_keys: ClassVar[Mapping[str, str]] = {
        "erp": "ODE-style error reduction per engine step of contacts and joint stops (default 0.2)",
        "bounce_erp": "error reduction of contacts that bounce; adds up to this to the rebound (default 0.05)",
        "engine_substeps": "MuJoCo steps per world substep (default 1)",
    }

    def __init__(self, world: CompiledWorld) -> None:
        super().__init__(world)
        self._opts = Options.parse(world.options_for(self.name))
        self._nsteps = world.substeps * self._opts.engine_substeps
        self._h = world.dt / self._nsteps
        with map_engine_errors(self.name, "building the model"):
            self._layout = build(world, self._opts, self._h)
            self._m = self._layout.model
            self._d = mujoco.MjData(self._m)
        m, lay = self._m, self._layout
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
        self._kinematic: dict[int, tuple[Vec3, Quat, Vec3, Vec3]] = {}
        self._xfrc = np.zeros((m.nbody, 6))
        self._forced = False
        motors = np.flatnonzero(lay.motor_id >= 0)
        self._motor_of = np.full(len(world.joints), -1)  # world joint -> slot = tendon id (one per motor)
        self._motor_of[motors] = lay.motor_id[motors]
        self._helper_dof = lay.helper_dof[motors][np.argsort(lay.motor_id[motors])]
        self._target = np.zeros(motors.size)  # per slot, in the MuJoCo joint's coordinate
        self._motor_sum = np.zeros(motors.size)
        self._earlier: list[_Pairs] = []  # grouped contacts of the step's engine steps but the last
        self._listed: list[Contact] | None = []  # None: the last engine step's contacts are still in MjData
        self._warnings = self._d.warning.number  # live views into MjData
        self._qpos, self._qvel = self._d.qpos, self._d.qvel
        owner = lay.geom_body
        n = len(world.bodies)  # geom pair -> code a*N+b of its bodies (a < b), for _touching
        self._pair_code = np.minimum.outer(owner, owner) * n + np.maximum.outer(owner, owner)
        rated = np.array([j for j, joint in enumerate(world.joints) if joint.kind in _RATED], dtype=np.int64)
        self._rated = rated  # the joints with a coordinate: slider, hinge
        self._rated_qpos, self._rated_dof = m.jnt_qposadr[lay.joint_id[rated]], m.jnt_dofadr[lay.joint_id[rated]]
        self._motored = motors  # world joints with a motor, their slots, signs
        self._motored_slot, self._motored_sign = self._motor_of[motors], self._sign[motors]
        self._steps = 0
        self._stale = True
        for i, body in enumerate(world.bodies):
            if body.motion is Motion.KINEMATIC:
                self._kinematic[i] = (body.pos, body.quat, body.lin_vel, body.ang_vel)
            elif body.motion is Motion.DYNAMIC:
                self._set_velocity(i, body.lin_vel, body.ang_vel)
        self._initial_joint_rates()
        for j, joint in enumerate(world.joints):
            if self._motor_of[j] >= 0:
                motor = joint.motor
                self.set_motor(j, motor.vel if motor else 0.0, motor.fmax if motor else 0.0)
        self._place_kinematic(0.0)

    # --- inputs ---------------------------------------------------------------------------------

    def set_kinematic(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        if body not in self._kinematic:
            raise UnsupportedFeature(f"mujoco: body `{self.world.bodies[body].name}` is not kinematic")
        self._kinematic[body] = (tuple(pos), tuple(quat), tuple(lin_vel), tuple(ang_vel))  # type: ignore[assignment]
        self._place_kinematic(0.0)

    def set_motor(self, joint: int, vel: float, fmax: float) -> None:
        slot = int(self._motor_of[joint])
        if slot < 0:
            spec = self.world.joints[joint]
            raise UnsupportedFeature(f"mujoco: joint `{spec.name}` ({spec.kind.value}) has no motor")
        self._m.tendon_frictionloss[slot] = fmax  # 0: no row, the motor is off
        self._target[slot] = self._sign[joint] * vel

    def apply_force(self, body: int, force: Vec3, torque: Vec3) -> None:
        if self.world.bodies[body].motion is not Motion.DYNAMIC:
            return  # static and kinematic bodies are unaffected by forces
        row = self._xfrc[self._layout.body_id[body]]
        row[:3] += force
        row[3:] += torque
        self._forced = True

    def reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        if body not in self._free or self.world.bodies[body].motion is not Motion.DYNAMIC:
            name = self.world.bodies[body].name
            raise UnsupportedFeature(f"mujoco: reset_body needs a free dynamic body; `{name}` is jointed")
        qadr, _ = self._free[body]
        self._d.qpos[qadr : qadr + 3] = pos
        self._d.qpos[qadr + 3 : qadr + 7] = quat
        self._set_velocity(body, lin_vel, ang_vel)
        self._stale = True

    # --- stepping -------------------------------------------------------------------------------

    def step(self) -> None:
        m, d, nsteps, motors = self._m, self._d, self._nsteps, self._helper_dof.size > 0
        earlier: list[_Pairs] = []
        with map_engine_errors(self.name, "mj_step"):
            if self._forced:
                d.xfrc_applied[:] = self._xfrc  # held for every substep of this step, then cleared
            if motors:
                self._motor_sum[:] = 0.0
            for k in range(nsteps):
                if k:
                    self._place_kinematic(k * self._h)
                if motors:
                    d.qvel[self._helper_dof] = self._target
                _coulomb.step(m, d)
                if motors:
                    self._motor_sum -= d.qfrc_constraint[self._helper_dof]  # the helper feels -(motor force)
                if k + 1 < nsteps:  # the last engine step's contacts stay in MjData until contacts() asks
                    earlier.append(self._touching())
            if self._forced:
                d.xfrc_applied[:] = 0.0
                self._xfrc[:] = 0.0
                self._forced = False
            self._steps += 1
            if self._kinematic:
                dt = self.world.dt
                for i, (pos, quat, lin, ang) in self._kinematic.items():  # now exactly where the velocity says
                    end = (pos[0] + lin[0] * dt, pos[1] + lin[1] * dt, pos[2] + lin[2] * dt)
                    self._kinematic[i] = (end, integrate_quat(quat, ang, dt), lin, ang)
                self._place_kinematic(0.0)
        self._earlier = earlier
        self._listed = None  # contacts() groups the last engine step's contacts when first asked
        self._stale = True
        self._check()

    def _place_kinematic(self, t: float) -> None:
        """Impose every kinematic body's pose at time ``t`` into the step, and its velocity."""
        for i, (pos, quat, lin, ang) in self._kinematic.items():
            qadr, _ = self._free[i]
            q = integrate_quat(quat, ang, t)
            self._d.qpos[qadr : qadr + 3] = (pos[0] + lin[0] * t, pos[1] + lin[1] * t, pos[2] + lin[2] * t)
            self._d.qpos[qadr + 3 : qadr + 7] = q
            self._set_velocity(i, lin, ang, q)
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
        if not self._warnings[_BAD].any() and np.isfinite(self._qpos).all() and np.isfinite(self._qvel).all():
            return
        d = self._d
        dofs = set(np.flatnonzero(~np.isfinite(d.qvel)))
        dofs |= {d.warning[w].lastinfo for w in _BAD_STATE[1:] if d.warning[w].number}  # lastinfo: the dof
        bad_bodies = {self._m.dof_bodyid[i] for i in dofs if 0 <= i < self._m.nv}
        named = [b.name for b, mj in zip(self.world.bodies, self._layout.body_id, strict=True) if mj in bad_bodies]
        body = named[0] if named else None
        time = self._steps * self.world.dt
        raise EngineFailure(
            f"mujoco: the simulation became invalid (NaN, inf or a huge acceleration) by t={time:g} s",
            backend=self.name,
            body=body,
            time=time,
        )

    # --- contacts -------------------------------------------------------------------------------

    def _touching(self) -> _Pairs:
        """Body pairs touching (distance <= 0) in the last engine step (MjData keeps them until the next)."""
        d, n = self._d, self._d.ncon
        if n == 0:
            return _NO_PAIRS
        c = d.contact
        dist, geom, rows = c.dist[:n], c.geom[:n], c.efc_address[:n]
        keep = dist <= 0.0
        if not keep.all():
            dist, geom, rows = dist[keep], geom[keep], rows[keep]
        code = self._pair_code[geom[:, 0], geom[:, 1]]
        # elliptic cone: a contact's first row is its normal; a contact at distance 0 is "in the gap":
        # touching, with no row (address -1, 0 N; efc_force[-1] is only read, then dropped, when nefc > 0)
        force = np.where(rows >= 0, d.efc_force[rows], 0.0) if d.nefc else np.zeros(rows.size)
        return _by_pair(code, -dist, force)

    def _merge(self, touching: list[_Pairs]) -> _Pairs:
        """Pairs touching in any engine step of the scenario step: most points, deepest, summed force."""
        if len(touching) == 1:
            return touching[0]
        code, points, depth, force = (np.concatenate(parts) for parts in zip(*touching, strict=True))
        return _by_pair(code, depth, force, points)

    def contacts(self) -> list[Contact]:
        if self._listed is None:  # first call since the step: group the last engine step's contacts now
            code, points, depth, force = self._merge([*self._earlier, self._touching()])
            n = len(self.world.bodies)
            mean = force / self._nsteps if self._nsteps > 1 else force  # force: the step's mean
            a, b = (code // n).tolist(), (code % n).tolist()
            rows = zip(a, b, points.tolist(), depth.tolist(), mean.tolist(), strict=True)
            self._listed = list(map(new_contact, rows))
        return self._listed.copy()

    # --- reads ----------------------------------------------------------------------------------

    def _refresh(self) -> None:
        """Recompute poses and velocities from qpos/qvel (mj_step leaves xpos/xquat one step behind)."""
        if self._stale:
            with map_engine_errors(self.name, "reading states"):
                mujoco.mj_kinematics(self._m, self._d)
                mujoco.mj_comPos(self._m, self._d)
                mujoco.mj_comVel(self._m, self._d)
            self._stale = False

    def body_states(self) -> BodyStates:
        self._refresh()
        d, ids = self._d, self._layout.body_id
        pos = d.xpos[ids]
        ang = d.cvel[ids, :3]
        r = pos - d.subtree_com[self._root]  # cvel is about the root's COM; np.cross's products, in its order:
        lin = d.cvel[ids, 3:] + (ang[:, _YZX] * r[:, _ZXY] - ang[:, _ZXY] * r[:, _YZX])
        return BodyStates(pos=pos, quat=d.xquat[ids], lin_vel=lin, ang_vel=ang)

    def joint_states(self) -> JointStates:
        n, rated, motored = len(self.world.joints), self._rated, self._motored
        position, velocity, force = np.full(n, np.nan), np.full(n, np.nan), np.zeros(n)
        if rated.size:
            sign = self._sign[rated]
            position[rated] = sign * self._qpos[self._rated_qpos]
            velocity[rated] = sign * self._qvel[self._rated_dof]
        if motored.size:
            force[motored] = self._motored_sign * self._motor_sum[self._motored_slot] / self._nsteps
        return JointStates(position=position, velocity=velocity, motor_force=force)

    def settings(self) -> dict[str, Any]:
        o = self._opts
        return {
            "engine": f"mujoco {mujoco.__version__}",
            "timestep": self._h,
            "engine_steps_per_step": self._nsteps,
            "integrator": "implicitfast",
            "cone": "elliptic",
            "solver": "Newton",
            "iterations": int(self._m.opt.iterations),
            "tolerance": float(self._m.opt.tolerance),
            "motors": "tendon frictionloss rows (bounded velocity constraints), impedance 0.9999",
            "contact_solref": f"(-erp/h^2, -(1+bounce)/h), erp {o.erp}, bounce_erp {o.bounce_erp}",
            "friction_solref": "(-1, -1/h)",
            "friction": f"Coulomb for mu <= {_coulomb.MU_COULOMB:g}: sliding contacts' normal reference corrected "
            f"for the convex cone (at most {_coulomb.MAX_SOLVES} solves per engine step, {_coulomb.TOLERANCE:g} m/s)",
            "impedance": IMPEDANCE,
            "mu_max": MU_MAX,
            "kinematic_mass_ratio": KINEMATIC_MASS_RATIO,
            "bounce_vel": "ignored (MuJoCo's contact is linear in the approach speed)",
        }


def _by_pair(code: np.ndarray, depth: np.ndarray, force: np.ndarray, points: np.ndarray | None = None) -> _Pairs:
    """Group rows by pair code: points (rows counted, or the largest given), deepest, summed force."""
    if code.size == 0:
        return _NO_PAIRS
    order = np.lexsort((depth, code))  # by pair, deepest last
    code, depth, force = code[order], depth[order], force[order]
    starts = np.empty(code.size, dtype=bool)
    starts[0] = True
    np.not_equal(code[1:], code[:-1], out=starts[1:])
    first = np.flatnonzero(starts)
    last = np.empty_like(first)
    last[:-1] = first[1:] - 1
    last[-1] = code.size - 1
    count = last - first + 1 if points is None else np.maximum.reduceat(points[order], first)
    return code[first], count, depth[last], np.add.reduceat(force, first)
