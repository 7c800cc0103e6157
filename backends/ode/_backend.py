"""OdeBackend: the reference backend, the Open Dynamics Engine itself through panda3d.ode (single precision).

Each engine step does what the lab's PyODE program does: collide, contact joints with the pair's surface,
forces of this scenario step (re-added for every substep: ODE clears them after each ``dWorldStep``),
``world.step`` or ``world.quickStep``, empty the contact group. Kinematic bodies are then put back
exactly on their commanded path and given their velocity again. ODE's own messages (``dMessage``) are
kept for ``drain_messages()`` instead of reaching stderr (``_native``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

import numpy as np
from panda3d.core import Datagram
from panda3d.ode import OdeJointFeedback, OdeUtil

from .._kit import BackendOptions, KinematicPose, SubstepContacts, SubstepMean, substep_times
from .._kit.stacks import Stacks, stacks
from ..base import Backend
from ..types import (
    MODEL_FILE_CAPABILITIES,
    BodyStates,
    Capability,
    CompiledWorld,
    Contact,
    ContactPoint,
    ImportedModel,
    JointStates,
    Motion,
    Precision,
    Quat,
    Vec3,
)
from . import _native
from ._build import JointHandle, axis_arg, build_scene, destroy_scene, panda_quat, set_motor
from ._contacts import Collider
from ._held import raise_held_inertia
from ._imported import read_imported
from ._joint_dynamics import JointDynamics, check_joint_dynamics
from ._mimic import Mimics, check_mimics
from ._motors import coordinate, effective_inertia, fudge_away, limit_state, motor_force, step_frame
from ._options import OdeOptions, check_resting_stack, check_stack
from ._ranges import check_ranges


def _has_friction(world: CompiledWorld) -> bool:
    """Whether any contact surface between bodies (the default or a pair's) has a Coulomb mu above 0."""
    return world.default_surface.mu > 0.0 or any(p.surface.mu > 0.0 for p in world.pair_surfaces)


def _free_stacks(world: CompiledWorld) -> Stacks:
    """The columns of bodies that no joint holds: a robot's links above one another are a chain, not a stack."""
    jointed = {j.body for j in world.joints} | {j.other for j in world.joints if j.other is not None}
    return stacks(replace(world, bodies=tuple(b for b in world.bodies if b.name not in jointed)))


class OdeBackend(Backend):
    """Adapter to ODE: a faithful replay of the lab's PyODE program, the referee of the other backends."""

    name = "ode"
    engine_distribution = "panda3d"
    #: everything but what only an engine building a robot from its model file runs (MJCF on MuJoCo), except
    #: joint springs. Armature is one more velocity row with CFM h / a on the joint's coordinate, springs a joint
    #: torque each step (_joint_dynamics), a mimic the force pair solved for each step (_mimic; docs/backends/ode.md)
    capabilities = frozenset(Capability) - (MODEL_FILE_CAPABILITIES - {Capability.JOINT_STIFFNESS})
    #: joint damping is ODE's own implicit row (CFM 1 / c, target 0, unbounded; _joint_dynamics): the runner's
    #: motor carries only the friction loss (its bound c |qdot| made Dantzig fail steps on pybullet_data's ant)
    native_damping: ClassVar[bool] = True
    #: panda3d builds ODE with dSINGLE: every state is a float32 (dGetConfiguration says "ODE_single_precision")
    precision = Precision.FLOAT32
    #: light bodies of a joint chain at 1e-3 of their body (1e-4 elsewhere): ODE's float32 LDLT meets a zero
    #: pivot at 1e-4 on dm_control's humanoids (backends/_kit/chains.py)
    chain_light: ClassVar[float] = 1e-3
    Options: ClassVar[type[BackendOptions]] = OdeOptions
    #: panda3d turns a failed C++ assertion (nassert) into AssertionError; ODE's own fatal errors abort.
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = (AssertionError,)
    options: OdeOptions

    @classmethod
    def engine_label(cls) -> str:
        return _native.label()

    @classmethod
    def engine_world(cls, world: CompiledWorld) -> CompiledWorld:
        """The base's world, with the inertia of bodies that joints hold still raised (``_held``: float32)."""
        return raise_held_inertia(super().engine_world(world))

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        check_joint_dynamics(world)
        check_ranges(world)
        check_mimics(world)  # one coupling per group of jointed bodies (_mimic)
        check_stack(stacks(world).landing)
        free = _free_stacks(world)
        check_resting_stack(free.tallest, free.landing, _has_friction(world))

    def _build(self) -> None:
        _native.install()
        self._messages: list[str] = []
        _native.attach()
        try:
            self._build_scene()
        except BaseException:
            _native.detach()
            raise
        self._messages.extend(_native.take())

    def _build_scene(self) -> None:
        world = self.world
        self._stacks = stacks(world)  # the registry refused columns too tall first (check_world)
        # quickstep reorders its rows with dRandInt, whose seed is the process's: a fresh process's (0) for each
        # world, so a scenario run twice in one process gives the same trace
        OdeUtil.randSetSeed(0)
        self._scene = build_scene(world, self.options)
        self._collider = Collider(
            self._scene,
            self.options.collide,
            self.options.contact_forces,
            f"ode-contacts-{id(self):x}",
            follow_slip=self.options.friction_pyramid == "slip",
            step=world.dt / world.substeps,
            impact_cfm=self.options.impact_cfm,
        )
        self._joint_dynamics = JointDynamics(self._scene.world, self._scene.joints, world.dt / world.substeps)
        self._mimics = Mimics(world, self._scene, effective_inertia)
        self._fudge = [j.joint.getParamFudgeFactor(*axis_arg(j)) if j.feedback else 1.0 for j in self._scene.joints]
        n = len(world.bodies)
        self._dynamic = [i for i, b in enumerate(world.bodies) if b.motion is Motion.DYNAMIC]
        self._dynamic_bodies = [self._scene.bodies[i] for i in self._dynamic]
        # Each body's state row (pos, quat, lin_vel, ang_vel): static rows set here, the others per read.
        self._fixed_rows = np.zeros((n, 13))
        for i, b in enumerate(world.bodies):
            if b.motion is Motion.STATIC:
                self._fixed_rows[i, 0:3], self._fixed_rows[i, 3:7] = b.pos, b.quat
        self._stepper = self._scene.world.step if self.options.stepper == "step" else self._scene.world.quickStep
        self._times = substep_times(world.dt, world.substeps)
        self._motor_mean = SubstepMean(len(world.joints))
        self._reactions = _watched(self._scene.joints, world.reaction_joints)
        self._reaction_mean = SubstepMean(6 * len(self._reactions))
        self._substep_contacts = SubstepContacts(world.substeps)
        self._states: BodyStates | None = None  # fresh states, dropped by anything that moves a body

    def _imported_model(self) -> ImportedModel:
        return read_imported(self.world, self._scene, self._joint_dynamics)

    def _settings(self) -> dict[str, Any]:
        o = self.options
        return {
            "engine": "ODE via panda3d.ode (single precision)",
            "stepper": "dWorldStep" if o.stepper == "step" else "dWorldQuickStep",
            "quickstep_iterations": o.quickstep_iterations,
            "erp": o.erp,
            "cfm": o.cfm,
            "stack_height": self._stacks.tallest,
            "max_correcting_vel": o.max_correcting_vel,
            "impact_cfm": "min(cfm, 1e-4 * h * (1/m1 + 1/m2)) above 1 cm/s" if o.impact_cfm else "off (world cfm)",
            "space": o.space,
            "collide": self._collider.mode,
            "contact_mode": "dContactBounce | dContactApprox1 (mu is a Coulomb coefficient)"
            + (" | dContactFDir1 along the slip" if o.friction_pyramid == "slip" else ""),
            "friction_pyramid": o.friction_pyramid,
            "contact_forces": o.contact_forces,
            "kinematic": "body with gravity off and 1e6 x the heaviest mass, re-placed after each step",
        }

    # --- stepping ------------------------------------------------------------------------------------

    def _step(self) -> None:
        world, scene, collider, stepper = self.world, self._scene, self._collider, self._stepper
        n = world.substeps
        h = world.dt / n
        joints = scene.joints
        forces = list(self.forces.items())
        pushed = dict(forces)
        every = n > 1  # with substeps, every substep's contacts are kept (the kit merges them)
        if joints:
            self._motor_mean.start()
        reactions = self._reactions
        if reactions:
            self._reaction_mean.start()
        if every:
            self._substep_contacts.start()
        for sub, t in enumerate(self._times):
            report = every or sub == n - 1
            collider.collide(report=report, forces=pushed)  # the friction directions predict the slip
            if self._joint_dynamics:  # armature rows' targets and springs' forces from the substep's start
                self._joint_dynamics.before_step()
            if not joints:
                self._issue(forces)
                stepper(h)
            else:
                limits = [limit_state(j) for j in joints]
                for k, j in enumerate(joints):
                    if limits[k]:
                        self._fudge_away(k, j, limits[k], h)
                frames = [step_frame(j) for j in joints]
                if self._mimics:  # trial steps from this state, the last one kept (_mimic)
                    self._mimics.step(lambda: self._issue(forces), stepper, h, self.steps * world.dt + t - h)
                else:
                    self._issue(forces)
                    stepper(h)
                fudge = self._fudge
                self._motor_mean.add([motor_force(j, limits[k], frames[k], fudge[k]) for k, j in enumerate(joints)])
            if reactions:  # dJointFeedback: the force on body 1 and the torque about its centre of mass
                self._reaction_mean.add([v for fb in reactions for a in (fb.getForce1(), fb.getTorque1()) for v in a])
            collider.after_step(report=report)
            if every:
                self._substep_contacts.add(collider.contacts())
            if self.kinematic:
                self._follow_track(t)
        if joints:
            self._motor_mean.finish()
        if reactions:
            self._reaction_mean.finish()
        self._states = None
        if self._mimics.messages:  # ODE's messages of the kept steps and the couplings' warnings, in order
            self._messages.extend(self._mimics.messages)
            self._mimics.messages.clear()
        self._messages.extend(_native.take())

    def _issue(self, forces: list[tuple[int, Any]]) -> None:
        """The substep's forces on the bodies and the springs' on their joints (ODE clears them after each step)."""
        bodies = self._scene.bodies
        for i, acc in forces:
            body = bodies[i]
            body.addForce(*acc[:3])  # type: ignore[union-attr]
            body.addTorque(*acc[3:])  # type: ignore[union-attr]
        if self._joint_dynamics:
            self._joint_dynamics.add_forces()

    def _fudge_away(self, k: int, handle: JointHandle, limit: int, h: float) -> None:
        """Set the fudge factor of a motor powering away from its stop (``_motors.fudge_away``), kept for its force."""
        fudge = fudge_away(handle, limit, h)
        if fudge is not None:
            self._fudge[k] = fudge

    def _follow_track(self, t: float) -> None:
        """Put each kinematic body where its velocity takes it ``t`` after the step began."""
        offsets = self._scene.offsets
        for i, pose in self.kinematic.items():
            pos, quat = pose.at(t)
            if i in offsets:
                self._place(i, pos, quat, pose.lin_vel, pose.ang_vel)
                continue
            body = self._scene.bodies[i]
            body.setPosition(*pos)  # type: ignore[union-attr]
            body.setQuaternion(panda_quat(quat))  # type: ignore[union-attr]
            body.setLinearVel(*pose.lin_vel)  # type: ignore[union-attr]
            body.setAngularVel(*pose.ang_vel)  # type: ignore[union-attr]

    # --- reading -------------------------------------------------------------------------------------

    def _read_rows(self) -> np.ndarray:
        """All bodies' states, one (N, 13) array: each row pos, quat, lin_vel, ang_vel."""
        rows = self._fixed_rows.copy()
        for i, pose in self.kinematic.items():  # the commanded pose, exact (ODE stores float32)
            row = rows[i]
            row[0:3], row[3:7], row[7:10], row[10:13] = pose.pos, pose.quat, pose.lin_vel, pose.ang_vel
        if self._dynamic:
            # Each vector written as ODE's float32 values (little-endian), widened to float64 exactly.
            dg = Datagram()
            for b in self._dynamic_bodies:
                b.getPosition().writeDatagramFixed(dg)  # type: ignore[union-attr]
                b.getQuaternion().writeDatagramFixed(dg)  # type: ignore[union-attr]
                b.getLinearVel().writeDatagramFixed(dg)  # type: ignore[union-attr]
                b.getAngularVel().writeDatagramFixed(dg)  # type: ignore[union-attr]
            rows[self._dynamic] = np.frombuffer(dg.getMessage(), dtype="<f4").reshape(-1, 13)
        for i, offset in self._scene.offsets.items():  # the OdeBody is at the COM: back to the body frame
            if i not in self.kinematic:
                offset.frame_row(rows[i])
        return rows

    def _body_states(self) -> BodyStates:
        if self._states is None:
            self._states = BodyStates.from_rows(self._read_rows())
        s = self._states
        return BodyStates(s.pos.copy(), s.quat.copy(), s.lin_vel.copy(), s.ang_vel.copy())

    def _joint_states(self) -> JointStates:
        if not self._scene.joints:
            return JointStates(np.zeros(0), np.zeros(0), np.zeros(0))
        read = [coordinate(j) for j in self._scene.joints]
        m = len(read)
        pos = np.array([r[0] for r in read], dtype=float).reshape(m)
        vel = np.array([r[1] for r in read], dtype=float).reshape(m)
        return JointStates(pos, vel, self._motor_mean.mean.copy())

    def _joint_reactions(self) -> np.ndarray:
        return self._reaction_mean.mean.reshape(-1, 6).copy()

    def _contacts(self) -> list[Contact]:
        if self.world.substeps > 1:
            return self._substep_contacts.merged() if self.steps else []
        return self._collider.contacts()

    def _contact_points(self) -> list[ContactPoint]:
        return self._collider.points() if self.steps else []

    def _drain_messages(self) -> list[str]:
        self._messages.extend(_native.take())
        out, self._messages = self._messages, []
        return out

    # --- inputs --------------------------------------------------------------------------------------

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self._place(body, pose.pos, pose.quat, pose.lin_vel, pose.ang_vel)

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        set_motor(self._scene.joints[joint], vel, fmax)

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self._place(body, pos, quat, lin_vel, ang_vel)
        self._joint_dynamics.forget()

    def _place(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        """Put the body FRAME at ``pos``/``quat`` with its origin moving at ``lin_vel`` (the OdeBody is its COM)."""
        offset = self._scene.offsets.get(body)
        if offset is not None:
            pos, lin_vel = offset.com_pose(pos, quat), offset.com_velocity(quat, lin_vel, ang_vel)
        ode_body = self._scene.bodies[body]
        ode_body.setPosition(*pos)  # type: ignore[union-attr]
        ode_body.setQuaternion(panda_quat(quat))  # type: ignore[union-attr]
        ode_body.setLinearVel(*lin_vel)  # type: ignore[union-attr]
        ode_body.setAngularVel(*ang_vel)  # type: ignore[union-attr]
        self._states = None

    # --- lifetime ------------------------------------------------------------------------------------

    def _close(self) -> None:
        _native.detach()
        self._joint_dynamics.destroy()
        destroy_scene(self._scene)


def _watched(handles: list[JointHandle], names: tuple[str, ...]) -> list[OdeJointFeedback]:
    """The feedback structures of the joints ``names`` (in that order), set on those that had none (ODE
    fills a joint's feedback at every step once set: the cost is only the watched joints')."""
    by_name = {h.spec.name: h for h in handles}
    out = []
    for name in names:
        handle = by_name[name]
        feedback = handle.feedback
        if feedback is None:  # a ball or fixed joint: its own, kept here (the handle's means "has a motor")
            feedback = OdeJointFeedback()  # Python owns it: ODE never frees feedback structs
            handle.joint.setFeedback(feedback)
        out.append(feedback)
    return out
