"""The Newton backend: the contract of backends/base.py on the Newton ``Model`` that ``_build`` makes.

One scenario step is ``world.substeps`` solver steps of ``dt / substeps``. Before each: the kinematic bodies get
their pose and velocity, ``State.clear_forces`` (Newton keeps ``body_f`` otherwise, and with two states it
comes back every other step) and the one-step forces go into ``body_f``, the motors' clamped forces into
``Control.joint_f`` (``_motors``), then the deterministic collision pipeline finds the contacts at the step's
start poses (ODE collides before stepping). After each: the contacts the solver used (separation <= 0) with
their normal forces (XPBD's ``CONTACT_F`` observable; Featherstone's penalty law). docs/backends/newton.md has
the mapping and its measured limits.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from .._kit import (
    BackendOptions,
    KinematicPose,
    SubstepContacts,
    SubstepMean,
    substep_times,
)
from .._kit.pairs import touching_pairs
from .._kit.stacks import free_bodies, stacks
from ..base import Backend
from ..errors import UnsupportedFeature
from ..geometry import quat_matrices
from ..types import (
    RIGID_BODY_CAPABILITIES,
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
from . import _motors, _warp
from ._build import build, rotate_xyzw, xyzw
from ._build import check as check_build
from ._contacts import read_contacts
from ._imported import read_imported
from ._options import NewtonOptions, check_stack


class NewtonBackend(Backend):
    """NVIDIA Newton (on Warp) with ODE semantics (docs/backends/newton.md)."""

    name: ClassVar[str] = "newton"
    engine_distribution: ClassVar[str] = "newton"
    precision: ClassVar[Precision] = Precision.FLOAT32  # Warp arrays of float32
    #: primitives, compound bodies, COM offsets and collision filters; no hulls or meshes yet (not mapped)
    capabilities: ClassVar[frozenset[Capability]] = RIGID_BODY_CAPABILITIES | {
        Capability.SHAPE_COMPOUND,
        Capability.COM_OFFSET,
        Capability.COLLISION_FILTER,
        Capability.CONTACT_POINTS,
    }
    Options: ClassVar[type[BackendOptions]] = NewtonOptions
    #: Warp raises RuntimeError for its own failures (a kernel that does not build, a device error)
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = (RuntimeError,)
    options: NewtonOptions

    @classmethod
    def engine_label(cls) -> str:
        from importlib.metadata import PackageNotFoundError, version

        try:
            warp = version("warp-lang")
        except PackageNotFoundError:
            warp = "not installed"
        return f"Newton {cls.engine_version()} (Warp {warp})"

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        check_build(world)
        free = stacks(free_bodies(world))
        check_stack(free.tallest, free.landing)
        if getattr(options, "solver", "xpbd") == "featherstone":
            names = [b.name for b in world.bodies]
            kinematic = [b.name for b in world.bodies if b.motion is Motion.KINEMATIC]
            if kinematic:
                raise UnsupportedFeature(
                    f"Backend `newton` with `solver: featherstone` does not carry kinematic bodies (measured: a cube "
                    f"on a platform moved 0.3 m ended 1.66 m behind it); `{kinematic[0]}` needs motion:kinematic; "
                    "use `solver: xpbd`."
                )
            for a, b in touching_pairs(world):
                if world.surface(names[a], names[b]).bounce > 0:
                    raise UnsupportedFeature(
                        f"Backend `newton` with `solver: featherstone` has no restitution coefficient (its penalty "
                        f"contacts bounce whatever is asked): the pair `{names[a]}`-`{names[b]}` needs "
                        "contact:bounce; use `solver: xpbd`."
                    )
        if getattr(options, "device", "cpu") == "cuda":
            wp, _ = _warp.load()
            _warp.device(wp, "cuda")

    # --- building -------------------------------------------------------------------------------------

    def _build(self) -> None:
        world = self.world
        wp, newton = _warp.load()
        self._wp, self._newton = wp, newton
        device = _warp.device(wp, self.options.device)
        self._built = built = build(wp, newton, world, self.options, device)
        self._model = model = built.model
        self._h = world.dt / world.substeps
        self._times = substep_times(world.dt, world.substeps)
        self._xpbd = self.options.solver == "xpbd"
        self._s0, self._s1 = model.state(), model.state()
        self._control = model.control()
        self._pipeline = newton.CollisionPipeline(model, deterministic=True)
        self._contacts_buf = self._pipeline.contacts()
        solvers = newton.solvers
        if self._xpbd:
            self._solver = solvers.SolverXPBD(model, iterations=self.options.iterations, enable_restitution=True)
            kind = self._solver.ObservableKind.CONTACT_F
            self._obs = self._solver.observables(kinds={kind}, contacts=self._contacts_buf)
        else:
            self._solver = solvers.SolverFeatherstone(model)
            self._obs = None
        n = len(world.bodies)
        self._body = np.asarray(built.body)
        self._moving = np.flatnonzero(self._body >= 0)
        self._com = np.array([b.com for b in world.bodies], dtype=float).reshape(n, 3)
        self._gravity = np.asarray(world.gravity, dtype=float)
        self._joints = built.joints
        self._motor = np.zeros((len(self._joints), 2))  # per joint: vel, fmax (world's sign)
        self._m_eff = np.array([_motors.effective_mass(h, world.bodies) if h.spec.kind in _RATED else 0.0
                                for h in self._joints])  # fmt: skip
        self._motor_mean = SubstepMean(len(self._joints))
        self._substep_contacts = SubstepContacts(world.substeps)
        self._contacts_now: list[Contact] = []
        self._points_now: list[ContactPoint] = []
        self._prev_angle = np.zeros(len(self._joints))
        self._jq = wp.zeros_like(model.joint_q)
        self._jqd = wp.zeros_like(model.joint_qd)
        self._initial_state()
        for j, handle in enumerate(self._joints):
            motor = handle.spec.motor
            if motor is not None and handle.spec.kind in _RATED:
                self._set_motor(j, motor.vel, motor.fmax)

    def _initial_state(self) -> None:
        """Poses from the model, velocities from the world: free bodies' COM twists, joints' relative rates."""
        world, model = self.world, self._model
        qd = model.joint_qd.numpy().copy()
        q_start = model.joint_q_start.numpy()
        qd_start = model.joint_qd_start.numpy()
        joint_child = model.joint_child.numpy()
        joint_type = model.joint_type.numpy()
        free = int(self._newton.JointType.FREE)
        child_of = {int(b): k for k, b in enumerate(joint_child)}
        for i, spec in enumerate(world.bodies):
            if spec.motion is not Motion.DYNAMIC:
                continue
            k = child_of.get(int(self._body[i]))
            if k is not None and int(joint_type[k]) == free:
                s = int(qd_start[k])
                qd[s : s + 3], qd[s + 3 : s + 6] = self._com_velocity(
                    i, spec.pos, spec.quat, spec.lin_vel, spec.ang_vel
                )
        bodies = world.bodies
        for handle in self._joints:
            joint = handle.spec
            if joint.kind not in _RATED:
                continue
            child = bodies[handle.child]
            parent = bodies[handle.parent] if handle.parent is not None else None
            lin = np.subtract(child.lin_vel, parent.lin_vel if parent else (0.0, 0.0, 0.0))
            ang = np.subtract(child.ang_vel, parent.ang_vel if parent else (0.0, 0.0, 0.0))
            rate = np.dot(lin if joint.kind is JointKind.SLIDER else ang, joint.axis)
            qd[int(qd_start[handle.index])] = float(rate)
        del q_start
        model.joint_qd.assign(qd)
        for state in (self._s0, self._s1):  # the states copied the model's rates when they were made
            state.joint_qd.assign(qd)
        self._newton.eval_fk(model, model.joint_q, model.joint_qd, self._s0)
        for i, pose in self.kinematic.items():
            self._put(i, pose, 0.0)

    def _com_velocity(self, i: int, pos: Any, quat: Any, lin: Any, ang: Any) -> tuple[np.ndarray, np.ndarray]:
        """A body origin's velocity as Newton's twist: the COM's linear velocity and the angular velocity."""
        w = np.asarray(ang, dtype=float)
        arm = quat_matrices(tuple(float(v) for v in quat)) @ self._com[i]
        return np.asarray(lin, dtype=float) + np.cross(w, arm), w

    def _settings(self) -> dict[str, Any]:
        o = self.options
        names = [b.name for b in self.world.bodies]
        out: dict[str, Any] = {
            "solver": o.solver,
            "device": o.device,
            "engine_dt": self._h,
            "engine_steps_per_step": self.world.substeps,
            "collision_pipeline": "deterministic",
            "motors": "generalised force clamped to fmax (joint_f), effective mass of the joint",
            "friction_per_body": dict(zip(names, self._built.surfaces.mu, strict=True)),
            "restitution_per_body": dict(zip(names, self._built.surfaces.restitution, strict=True)),
        }
        if self._xpbd:
            out["iterations"] = o.iterations
        else:
            out.update(contact_stiffness=o.contact_stiffness, limit_stiffness=o.limit_stiffness,
                       limit_damping=o.limit_damping)  # fmt: skip
        return out

    # --- inputs ---------------------------------------------------------------------------------------

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        self._motor[joint] = (vel, fmax)

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self._put(body, pose, 0.0)

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self._write_body(body, pos, quat, lin_vel, ang_vel)

    def _put(self, body: int, pose: KinematicPose, t: float) -> None:
        pos, quat = pose.at(t)
        self._write_body(body, pos, quat, pose.lin_vel, pose.ang_vel)

    def _write_body(self, body: int, pos: Any, quat: Any, lin: Any, ang: Any) -> None:
        k = int(self._body[body])
        q = self._s0.body_q.numpy().copy()
        qd = self._s0.body_qd.numpy().copy()
        q[k, :3], q[k, 3:] = pos, xyzw(quat)
        qd[k, :3], qd[k, 3:] = self._com_velocity(body, pos, quat, lin, ang)
        self._s0.body_q.assign(q)
        self._s0.body_qd.assign(qd)
        if not self._xpbd:  # Featherstone integrates the joint coordinates: the root's free joint too
            self._write_free_joint(k, q[k], qd[k])

    def _write_free_joint(self, k: int, q: np.ndarray, qd: np.ndarray) -> None:
        model = self._model
        child = model.joint_child.numpy()
        joint = int(np.flatnonzero(child == k)[0])
        s, sd = int(model.joint_q_start.numpy()[joint]), int(model.joint_qd_start.numpy()[joint])
        jq, jqd = self._s0.joint_q.numpy().copy(), self._s0.joint_qd.numpy().copy()
        jq[s : s + 7], jqd[sd : sd + 6] = q, qd
        self._s0.joint_q.assign(jq)
        self._s0.joint_qd.assign(jqd)

    # --- stepping -------------------------------------------------------------------------------------

    def _step(self) -> None:
        n = self.world.substeps
        applied = self._applied()
        motors = bool((self._motor[:, 1] > 0).any())
        self._motor_mean.start()
        self._substep_contacts.start()
        for k in range(n):
            if k:
                for i, pose in self.kinematic.items():
                    self._put(i, pose, self._times[k - 1])
            s0 = self._s0
            s0.clear_forces()
            if applied is not None:
                s0.body_f.assign(applied)
            force = self._motor_forces(applied) if motors else np.zeros(len(self._joints))
            self._motor_mean.add(force)
            self._pipeline.collide(s0, self._contacts_buf)
            before = s0.body_q.numpy().copy()
            if self._obs is not None:
                self._solver.step(s0, self._s1, self._control, self._contacts_buf, self._h, observables=self._obs)
            else:
                self._solver.step(s0, self._s1, self._control, self._contacts_buf, self._h)
            self._s0, self._s1 = self._s1, self._s0
            self._substep_contacts.add(self._read_contacts(before, points=k == n - 1 and self.world.contact_points))
        self._motor_mean.finish()
        dt = self.world.dt
        for i, pose in self.kinematic.items():
            self._put(i, KinematicPose(*pose.at(dt), pose.lin_vel, pose.ang_vel), 0.0)
        self._contacts_now = self._substep_contacts.merged()

    def _applied(self) -> np.ndarray | None:
        """The step's one-step forces as Newton's ``body_f`` rows (force, torque at the COM, world frame)."""
        forces = list(self.forces.items())
        if not forces:
            return None
        out = np.zeros((len(self._s0.body_f), 6), dtype=np.float32)
        for i, acc in forces:
            out[int(self._body[i])] = acc
        return out

    def _rates(self) -> np.ndarray:
        """Newton's joint rates now (XPBD moves bodies only: the joint state comes from ``eval_ik``)."""
        if self._xpbd:
            self._newton.eval_ik(self._model, self._s0, self._jq, self._jqd)
            return np.asarray(self._jqd.numpy())
        return np.asarray(self._s0.joint_qd.numpy())

    def _motor_forces(self, applied: np.ndarray | None) -> np.ndarray:
        """Each motor's force for the coming engine step (world's sign), written into ``joint_f`` (Newton's)."""
        rates = self._rates()
        joint_f = np.zeros(len(self._model.joint_qd), dtype=np.float32)
        out = np.zeros(len(self._joints))
        q = self._s0.body_q.numpy() if applied is not None or self._gravity.any() else None
        for j, handle in enumerate(self._joints):
            vel, fmax = self._motor[j]
            if fmax <= 0.0 or handle.spec.kind not in _RATED:
                continue
            qd_index = int(self._model.joint_qd_start.numpy()[handle.index])
            wanted = self._m_eff[j] * (handle.sign * vel - float(rates[qd_index])) / self._h
            if handle.parent is None and q is not None:
                k = int(self._body[handle.child])
                com = q[k, :3] + rotate_xyzw(q[k, 3:], self._com[handle.child])
                row = applied[k] if applied is not None else None
                wanted -= _motors.bias(handle, self.world.bodies[handle.child], com, self._gravity, row)
            force = min(fmax, max(-fmax, wanted))
            joint_f[qd_index] = force
            out[j] = handle.sign * force
        self._control.joint_f.assign(joint_f)
        return out

    def _read_contacts(self, body_q: np.ndarray, points: bool = False) -> list[Contact]:
        """The touching contacts of the engine step just taken (``_contacts.read_contacts``); ``points``: keep its
        touching points too."""
        found, touching_points = read_contacts(self._contacts_buf, body_q, self._built.shape_owner, self._body,
                                               self._obs, self.options.contact_stiffness, len(self.world.bodies),
                                               points)  # fmt: skip
        if touching_points is not None:
            self._points_now = touching_points
        return found

    # --- outputs --------------------------------------------------------------------------------------

    def _body_states(self) -> BodyStates:
        n = len(self.world.bodies)
        pos = np.array([b.pos for b in self.world.bodies], dtype=float).reshape(n, 3)
        quat = np.array([b.quat for b in self.world.bodies], dtype=float).reshape(n, 4)
        lin, ang = np.zeros((n, 3)), np.zeros((n, 3))
        q = self._s0.body_q.numpy().astype(float)
        qd = self._s0.body_qd.numpy().astype(float)
        for i in self._moving.tolist():
            k = int(self._body[i])
            pos[i] = q[k, :3]
            quat[i] = (q[k, 6], q[k, 3], q[k, 4], q[k, 5])
            w = qd[k, 3:]
            lin[i] = qd[k, :3] - np.cross(w, rotate_xyzw(q[k, 3:], self._com[i]))
            ang[i] = w
        for i, pose in self.kinematic.items():  # exactly where the contract puts them (float32 aside)
            pos[i], quat[i], lin[i], ang[i] = pose.pos, pose.quat, pose.lin_vel, pose.ang_vel
        return BodyStates(pos, quat, lin, ang)

    def _joint_states(self) -> JointStates:
        m = len(self._joints)
        position, velocity = np.full(m, math.nan), np.full(m, math.nan)
        if m:
            if self._xpbd:
                self._newton.eval_ik(self._model, self._s0, self._jq, self._jqd)
                jq, jqd = self._jq.numpy(), self._jqd.numpy()
            else:
                jq, jqd = self._s0.joint_q.numpy(), self._s0.joint_qd.numpy()
            q_start = self._model.joint_q_start.numpy()
            qd_start = self._model.joint_qd_start.numpy()
            for j, handle in enumerate(self._joints):
                if handle.spec.kind not in _RATED:
                    continue
                value = handle.sign * float(jq[int(q_start[handle.index])])
                if handle.spec.kind is JointKind.HINGE and math.isfinite(value):  # continuous through +-pi
                    value += 2.0 * math.pi * round((self._prev_angle[j] - value) / (2.0 * math.pi))
                    self._prev_angle[j] = value
                position[j] = value
                velocity[j] = handle.sign * float(jqd[int(qd_start[handle.index])])
        return JointStates(position, velocity, self._motor_mean.mean.copy())

    def _contacts(self) -> list[Contact]:
        return list(self._contacts_now)

    def _contact_points(self) -> list[ContactPoint]:
        return list(self._points_now)

    def _imported_model(self) -> ImportedModel:
        return read_imported(self.world, self._built, self._s0.body_q.numpy().astype(float))

    def _close(self) -> None:
        self._solver = None
        self._pipeline = None


_RATED = (JointKind.SLIDER, JointKind.HINGE)
