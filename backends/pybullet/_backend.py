"""The PyBullet adapter: ODE semantics on PyBullet in DIRECT mode (docs/backends/pybullet.md).

One client per instance (several may coexist; every call passes ``physicsClientId``). Each scenario
step is ``world.substeps`` calls of ``stepSimulation()`` with ``fixedTimeStep = dt / substeps`` and
``numSubSteps = 0``; damping is 0 everywhere; one-step forces are re-applied before every substep of
the next step (PyBullet clears them after each); kinematic bodies are mass-0 bases placed with their
velocity and re-placed exactly after each substep. With substeps, every substep's contacts are grouped
and the kit merges them (backends/base.py: the contacts used during the step).
"""

from __future__ import annotations

import math
from itertools import chain
from typing import Any, ClassVar

import numpy as np
import pybullet as p

from .._kit import BackendOptions, KinematicPose, SubstepContacts, SubstepMean, substep_times
from .._kit.stacks import stack_height
from ..base import Backend
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
    ShapeKind,
    Vec3,
)
from ._build import PLANE_HALF_SIZE, Layout, build, initial_rate, xyzw
from ._build import check as check_build
from ._frames import InertialFrames
from ._impacts import ImpactErp
from ._imported import read_imported
from ._options import PyBulletOptions, check_stack, solver_iterations
from ._reads import ROW, ContactReader, base_rows
from ._rotors import add_mimics, add_rotors
from ._springs import Springs
from ._surfaces import FRICTION_CLAMP, SurfaceFit, fit_surfaces

_flat = chain.from_iterable

_NAME = "pybullet"
#: PyBullet clamps joint rates and free bases' speeds to 100 by default; ODE has no such limit.
_MAX_JOINT_VELOCITY = 1e6
#: Bullet keeps contact points up to this distance apart (default 0.02 m). Restitution is lost when a
#: point exists more than about one step before impact [checked: a sphere dropped 0.5 m at dt 0.001
#: rebounds to 0.0000 of its height at 0.02, 0.27 at 0.001]. ODE makes contacts only when touching.
#: NB: Bullet keeps this in a process-wide global, so every instance sets the same value.
CONTACT_BREAKING_THRESHOLD = 0.001
#: Collision margin of a body with convex hulls. PyBullet gives a hull built from vertices a 1 mm margin
#: that Bullet adds OUTSIDE the vertices (primitives keep theirs inside): a hull box rested 0.99 mm high
#: [checked]. Margin 0 rests at -1.0e-5 m but on 1 contact point (it rocks, as on GEOM_PLANE); 1e-4 keeps
#: 4 points and rests at +1.5e-5 m, the primitive box's -1.4e-5 m in size [checked, dt 0.01].
HULL_MARGIN = 1e-4
#: restitutionVelocityThreshold = bounce_vel + this * |g| * h (see PyBulletBackend._build_world).
_GRAVITY_MARGIN = 1.5
#: The quaternion's columns in a state row, in (w, x, y, z) order.
_WXYZ = np.array([6, 3, 4, 5])


class PyBulletBackend(Backend):
    """PyBullet multibodies with ODE's stepping, forces, motors, stops and surfaces."""

    name: ClassVar[str] = _NAME
    engine_distribution: ClassVar[str] = "pybullet"
    #: Bullet's btScalar is double in pybullet's build (BT_USE_DOUBLE_PRECISION)
    precision: ClassVar[Precision] = Precision.FLOAT64
    capabilities: ClassVar[frozenset[Capability]] = RIGID_BODY_CAPABILITIES | {
        Capability.CONTACT_POINTS,
        Capability.JOINT_ARMATURE,  # a rotor geared to the joint (_rotors)
        Capability.JOINT_MIMIC,  # a gear constraint between the two joints (_rotors)
        Capability.JOINT_STIFFNESS,  # the spring's torque each engine step (_springs)
        Capability.SHAPE_COMPOUND,
        Capability.SHAPE_CONVEX,
        Capability.COM_OFFSET,
        Capability.COLLISION_FILTER,
        Capability.JOINT_REACTION,  # enableJointForceTorqueSensor
    }
    Options: ClassVar[type[BackendOptions]] = PyBulletOptions
    #: pybullet raises only ``pybullet.error`` (a failed command, a lost client).
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = (p.error,)
    options: PyBulletOptions

    @classmethod
    def engine_label(cls) -> str:
        return f"Bullet (pybullet {cls.engine_version()})"  # Bullet exposes no version of its own here

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        if isinstance(options, PyBulletOptions) and options.solver_iterations is None:
            check_stack(stack_height(world))  # set by hand, the column is the scenario's to judge
        check_build(world)

    def _build(self) -> None:
        self._c = int(p.connect(p.DIRECT))
        try:
            self._build_world()
        except BaseException:
            p.disconnect(physicsClientId=self._c)
            raise

    # --- construction ---------------------------------------------------------------------------

    def _build_world(self) -> None:
        world, c = self.world, self._c
        self._h = world.dt / world.substeps
        p.setGravity(*world.gravity, physicsClientId=c)
        p.setTimeStep(self._h, physicsClientId=c)
        self._layout: Layout = build(p, c, world)
        self._frames = InertialFrames(world)
        #: per joint tuple ``set_motors`` was given: (multibody, its links, (place in the tuple, sign) each)
        self._motor_groups: dict[tuple[int, ...], list[tuple[int, list[int], list[tuple[int, float]]]]] = {}
        self._fit: SurfaceFit = fit_surfaces(world)
        # ODE bounces when the approach speed *before* the step exceeds bounce_vel; Bullet compares the
        # speed after this substep's gravity, so a resting body approaches at about g*h and bounces every
        # step [checked: the lab's box on the door, dt 0.04, bounce 0.2, threshold 0: vz -0.32..+0.33
        # forever; threshold exactly g*h: a limit cycle that rocks the box]. Add 1.5 g*h (1.1 already
        # rests still; 1.5 leaves a margin).
        self._threshold = self._fit.restitution_threshold + _GRAVITY_MARGIN * math.hypot(*world.gravity) * self._h
        self._stack = stack_height(world)  # the registry refused a column too tall first (check_world)
        self._iterations = solver_iterations(self.options, self._stack)
        p.setPhysicsEngineParameter(
            fixedTimeStep=self._h,
            numSubSteps=0,
            numSolverIterations=self._iterations,
            restitutionVelocityThreshold=self._threshold,
            contactBreakingThreshold=CONTACT_BREAKING_THRESHOLD,
            deterministicOverlappingPairs=int(self.options.deterministic_overlapping_pairs),
            physicsClientId=c,
        )
        layout = self._layout
        # PyBullet pitfall [checked]: a changeDynamics call on a link that also sets linearDamping,
        # angularDamping or activationState applies its other parameters to the base instead (and
        # drops joint limits). These three are per multibody anyway: set them alone, on the base.
        for uid in sorted(set(layout.uid)):
            for key, value in (
                ("linearDamping", 0.0),
                ("angularDamping", 0.0),
                ("activationState", p.ACTIVATION_STATE_DISABLE_SLEEPING),
            ):
                p.changeDynamics(uid, -1, physicsClientId=c, **{key: value})
        for i, spec in enumerate(world.bodies):
            uid, link = layout.uid[i], layout.link[i]
            extra: dict[str, Any] = {}
            if spec.motion is Motion.DYNAMIC:
                extra["localInertiaDiagonal"] = list(spec.inertia)
            p.changeDynamics(
                uid,
                link,
                restitution=self._fit.restitution[i],
                lateralFriction=self._fit.friction[i],
                physicsClientId=c,
                **extra,
            )
            # alone: combined with other parameters it misroutes them, like the damping. On a base it lifts
            # Bullet's 100 m/s cap on free bodies [checked: 2000 N for 0.04 s on 0.5 kg gave 100.0, now 160.0]
            p.changeDynamics(uid, link, maxJointVelocity=_MAX_JOINT_VELOCITY, physicsClientId=c)
            if any(one.shape.kind is ShapeKind.CONVEX for one in spec.placed_shapes()):  # alone, as above
                p.changeDynamics(uid, link, collisionMargin=HULL_MARGIN, physicsClientId=c)
            if link < 0:  # the COM's velocity (the body's origin's, given, plus omega x arm)
                lin = self._frames.to_inertial(i, spec.pos, spec.quat, spec.lin_vel, spec.ang_vel)[2]
                p.resetBaseVelocity(uid, list(lin), list(spec.ang_vel), physicsClientId=c)
        rates: dict[int, float] = {}
        for k, joint in enumerate(world.joints):
            handle = layout.joints[k]
            if joint.kind is JointKind.BALL:  # PyBullet holds spherical links with a default motor
                p.setJointMotorControlMultiDof(
                    handle.uid,
                    handle.link,
                    p.POSITION_CONTROL,
                    targetPosition=[0.0, 0.0, 0.0, 1.0],
                    force=[0.0, 0.0, 0.0],
                    physicsClientId=c,
                )
            if handle.dofs != 1:
                continue
            motor = joint.motor
            self._set_motor(k, motor.vel if motor else 0.0, motor.fmax if motor else 0.0)
            if joint.lo is not None or joint.hi is not None:  # in its own call: never with damping
                lo = joint.lo if joint.lo is not None else -math.inf
                hi = joint.hi if joint.hi is not None else math.inf
                lo, hi = (lo, hi) if handle.sign > 0 else (-hi, -lo)
                p.changeDynamics(
                    handle.uid,
                    handle.link,
                    jointLowerLimit=max(lo, -1e30),
                    jointUpperLimit=min(hi, 1e30),
                    physicsClientId=c,
                )
            rate = initial_rate(world, joint)
            rates[k] = handle.sign * rate
            if rate:  # a link's initial velocity is its joint rate (ball and fixed children inherit)
                p.resetJointState(handle.uid, handle.link, 0.0, handle.sign * rate, physicsClientId=c)
        add_rotors(p, c, world, layout, rates)  # joint armature: a rotor geared to the joint (_rotors)
        add_mimics(p, c, world, layout)  # URDF <mimic>: a gear between the two joints (_rotors)
        self._springs = Springs(world, layout)  # joint stiffness: the spring's torque each engine step (_springs)
        bases = [i for i in range(len(world.bodies)) if layout.link[i] < 0]
        self._base_uids = [layout.uid[i] for i in bases]
        self._base_rows = None if bases == list(range(len(world.bodies))) else bases  # None: every body, in order
        self._motor_joints = [k for k, h in enumerate(layout.joints) if h.dofs == 1]
        uids = sorted({layout.joints[k].uid for k in self._motor_joints})
        #: per multibody, its 1-dof joints' links, for one getJointStates call each; then the world joints
        #: those rows are, and their signs
        self._joint_reads = [(u, [layout.joints[k].link for k in self._motor_joints if layout.joints[k].uid == u])
                             for u in uids]  # fmt: skip
        order = [k for u in uids for k in self._motor_joints if layout.joints[k].uid == u]
        self._joint_order = np.array(order, dtype=np.int64)
        self._joint_sign = np.array([layout.joints[k].sign for k in order], dtype=float)
        #: every joint read, in world order (a robot of hinges and sliders): the read's columns are the arrays
        self._every_joint = order == list(range(len(world.joints)))
        self._motor_mean = SubstepMean(len(world.joints))
        self._watched = self._watch_reactions()
        self._reaction_mean = SubstepMean(6 * len(self._watched))
        self._times = substep_times(world.dt, world.substeps)
        self._substep_contacts = SubstepContacts(world.substeps)
        lut = np.full((max(layout.uid) + 1, max(layout.link) + 2), -1, dtype=np.int64)
        for i in range(len(world.bodies)):
            lut[layout.uid[i], layout.link[i] + 1] = i
        self._contact_reader = ContactReader(lut.tolist(), len(world.bodies))  # (multibody, link + 1) -> body
        kick = math.hypot(*world.gravity) * self._h
        self._impacts = ImpactErp(c, lut.tolist(), self._fit.restitution, self._threshold, kick)
        self._cache: np.ndarray | None = None
        self._listed: list[Contact] | None = None

    # --- stepping -------------------------------------------------------------------------------

    def _step(self) -> None:
        c, n = self._c, self.world.substeps
        motors = n > 1 and bool(self._motor_joints)  # the substeps' motor torques, for their mean
        if n == 1 and not (self.forces or self.kinematic or self._impacts.active or self._watched or self._springs):
            p.stepSimulation(c)
        else:
            self._step_with_inputs(c, n, motors)
        self._cache = None
        self._listed = None

    def _step_with_inputs(self, c: int, n: int, motors: bool) -> None:
        """The substeps with one-step forces, kinematic bodies, motor torques or contacts to collect."""
        if motors:
            self._motor_mean.start()
        if self._watched:
            self._reaction_mean.start()
        if n > 1:
            self._substep_contacts.start()
        for t in self._times:
            if self.forces:
                self._apply_forces()
            if self._impacts.active:
                self._impacts.before_substep(self._fresh_rows)
            if self._springs:
                self._springs.apply(p, c)
            p.stepSimulation(physicsClientId=c)
            if self.kinematic:
                self._follow_track(t)
            if motors:
                self._motor_mean.add(self._motor_torques())
            if self._watched:
                self._reaction_mean.add(self._reactions_now())
            if n > 1:
                self._substep_contacts.add(self._contact_reader(p.getContactPoints(physicsClientId=c)))
        if motors:
            self._motor_mean.finish()
        if self._watched:
            self._reaction_mean.finish()

    def _watch_reactions(self) -> list[tuple[int, int, float, int, int, tuple[float, ...], bool]]:
        """A force/torque sensor on each joint of ``world.reaction_joints``, reporting in world axes about the
        joint's pivot (the child link's frame origin: jointFeedbackMode world space | joint frame); per joint
        (multibody, link, +1 when the link is the joint's first body else -1, the first body's multibody and
        link, the joint's axis in the link frame for a motor's torque (empty without one), whether it is a
        slider). The sensor leaves out what a joint's motor applies along its axis: added from its applied
        torque (getJointState's fourth value, the coordinate's force). Only when the scenario reads a
        reaction: the mode is the client's, the sensors cost a pass."""
        names = self.world.reaction_joints
        if not names:
            return []
        c, layout = self._c, self._layout
        p.setPhysicsEngineParameter(
            jointFeedbackMode=p.JOINT_FEEDBACK_IN_WORLD_SPACE | p.JOINT_FEEDBACK_IN_JOINT_FRAME, physicsClientId=c
        )
        index = {j.name: k for k, j in enumerate(self.world.joints)}
        out = []
        for name in names:
            k = index[name]
            handle = layout.joints[k]
            first = self.world.body_index(self.world.joints[k].body)
            p.enableJointForceTorqueSensor(handle.uid, handle.link, True, physicsClientId=c)
            axis = tuple(p.getJointInfo(handle.uid, handle.link, physicsClientId=c)[13]) if handle.dofs == 1 else ()
            slider = self.world.joints[k].kind is JointKind.SLIDER
            out.append((handle.uid, handle.link, handle.sign, layout.uid[first], layout.link[first], axis, slider))
        return out

    def _reactions_now(self) -> list[float]:
        """The watched joints' wrenches on their first bodies after this engine step: force, and torque about
        the first body's centre of mass (moved from the pivot: tau_c = tau_p + (pivot - c) x F)."""
        c, out = self._c, []  # type: tuple[int, list[float]]
        for uid, link, sign, body_uid, body_link, axis, slider in self._watched:
            state = p.getJointState(uid, link, physicsClientId=c)
            frame = p.getLinkState(uid, link, physicsClientId=c)
            pivot, wrench = np.asarray(frame[4]), np.array(state[2])
            if axis:  # the motor's force or torque along the axis (the link frame's orientation: frame[5])
                turn = np.asarray(p.getMatrixFromQuaternion(frame[5], physicsClientId=c)).reshape(3, 3)
                along = state[3] * (turn @ np.asarray(axis))
                wrench[0:3] += along if slider else 0.0
                wrench[3:6] += 0.0 if slider else along
            if body_link < 0:
                com = np.asarray(p.getBasePositionAndOrientation(body_uid, physicsClientId=c)[0])
            else:
                com = np.asarray(p.getLinkState(body_uid, body_link, physicsClientId=c)[0])
            force, torque = sign * np.asarray(wrench[:3]), sign * np.asarray(wrench[3:])
            out.extend((*force, *(torque + np.cross(pivot - com, force))))
        return out

    def _joint_reactions(self) -> np.ndarray:
        return self._reaction_mean.mean.reshape(-1, 6).copy()

    def _follow_track(self, t: float) -> None:
        """PyBullet does not move mass-0 bases: put each kinematic body where its velocity says at ``t``."""
        c = self._c
        for i, pose in self.kinematic.items():
            uid = self._layout.uid[i]
            pos, quat = pose.at(t)
            pos, quat, lin = self._frames.to_inertial(i, pos, quat, pose.lin_vel, pose.ang_vel)
            p.resetBasePositionAndOrientation(uid, pos, xyzw(quat), physicsClientId=c)
            p.resetBaseVelocity(uid, lin, pose.ang_vel, physicsClientId=c)

    def _apply_forces(self) -> None:
        """At the centre of mass, world frame, for this substep (PyBullet clears them after each)."""
        c, layout = self._c, self._layout
        for i, ft in self.forces.items():
            uid, link = layout.uid[i], layout.link[i]
            if link < 0:
                com = p.getBasePositionAndOrientation(uid, physicsClientId=c)[0]
            else:
                com = p.getLinkState(uid, link, computeForwardKinematics=1, physicsClientId=c)[0]
            p.applyExternalForce(uid, link, ft[:3].tolist(), com, p.WORLD_FRAME, physicsClientId=c)
            p.applyExternalTorque(uid, link, ft[3:].tolist(), p.WORLD_FRAME, physicsClientId=c)

    def _motor_torques(self) -> np.ndarray:
        out = np.zeros(len(self.world.joints))
        for k in self._motor_joints:
            h = self._layout.joints[k]
            out[k] = h.sign * p.getJointState(h.uid, h.link, physicsClientId=self._c)[3]
        return out

    # --- reading --------------------------------------------------------------------------------

    def _fresh_rows(self) -> np.ndarray:
        """The bodies' states now (between substeps the cache is stale)."""
        self._cache = None
        return self._read()

    def _read(self) -> np.ndarray:
        if self._cache is not None:
            return self._cache
        c = self._c
        arr = base_rows(c, self._base_uids)
        if self._base_rows is not None:  # some bodies are links of jointed trees
            bases, arr = arr, np.empty((len(self.world.bodies), ROW))
            arr[self._base_rows] = bases
            for uid, links, bodies in self._layout.link_groups:
                states = p.getLinkStates(
                    uid, links, computeLinkVelocity=1, computeForwardKinematics=1, physicsClientId=c
                )
                values = _flat(_flat((ls[0], ls[1], ls[6], ls[7]) for ls in states))  # pos, xyzw, lin, ang
                arr[bodies] = np.fromiter(values, np.float64, ROW * len(links)).reshape(-1, ROW)
        if self._frames.offsets:  # inertial frames -> body frames
            self._frames.to_body(arr)
        self._cache = arr
        return arr

    def _body_states(self) -> BodyStates:
        arr = self._read()
        return BodyStates(
            pos=arr[:, 0:3].copy(),
            quat=arr[:, _WXYZ],  # x, y, z, w -> w, x, y, z
            lin_vel=arr[:, 7:10].copy(),
            ang_vel=arr[:, 10:13].copy(),
        )

    def _joint_states(self) -> JointStates:
        m, c = len(self.world.joints), self._c
        if self._joint_reads:  # one getJointStates per multibody: (q, qd, reaction forces, applied torque)
            states = [s for uid, links in self._joint_reads for s in p.getJointStates(uid, links, physicsClientId=c)]
            rows = np.fromiter(_flat((s[0], s[1], s[3]) for s in states), np.float64, 3 * len(states))
            rows = rows.reshape(-1, 3) * self._joint_sign[:, None]
            if self._every_joint:
                pos, vel, force = np.ascontiguousarray(rows.T)  # three contiguous rows: the same numbers
            else:
                pos, vel, force = np.full(m, np.nan), np.full(m, np.nan), np.zeros(m)
                order = self._joint_order
                pos[order], vel[order], force[order] = rows[:, 0], rows[:, 1], rows[:, 2]
        else:
            pos, vel, force = np.full(m, np.nan), np.full(m, np.nan), np.zeros(m)
        if self.world.substeps > 1 and self.steps:
            force = self._motor_mean.mean.copy()  # the mean over the step's substeps
        return JointStates(position=pos, velocity=vel, motor_force=force)

    def _contacts(self) -> list[Contact]:
        if self._listed is None:
            if self.world.substeps > 1:
                self._listed = self._substep_contacts.merged() if self.steps else []
            else:
                self._listed = self._contact_reader(p.getContactPoints(physicsClientId=self._c))
        return list(self._listed)

    def _contact_points(self) -> list[ContactPoint]:
        return self._contact_reader.points(p.getContactPoints(physicsClientId=self._c)) if self.steps else []

    # --- inputs ---------------------------------------------------------------------------------

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        uid = self._layout.uid[body]
        pos, quat, lin = self._frames.to_inertial(body, pose.pos, pose.quat, pose.lin_vel, pose.ang_vel)
        p.resetBasePositionAndOrientation(uid, list(pos), xyzw(quat), physicsClientId=self._c)
        p.resetBaseVelocity(uid, list(lin), list(pose.ang_vel), physicsClientId=self._c)
        self._cache = None

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        h = self._layout.joints[joint]
        p.setJointMotorControl2(
            h.uid, h.link, p.VELOCITY_CONTROL, targetVelocity=h.sign * vel, force=fmax, physicsClientId=self._c
        )

    def _set_motors(self, joints: tuple[int, ...], vels: list[float], fmaxes: list[float]) -> None:
        """One ``setJointMotorControlArray`` per multibody: the same motor settings as ``setJointMotorControl2``
        per joint (velocity control: target rate, maximum force, velocity gain 1)."""
        groups = self._motor_groups.get(joints)
        if groups is None:
            handles = [self._layout.joints[k] for k in joints]
            groups = [(uid, [h.link for h in handles if h.uid == uid],
                       [(i, h.sign) for i, h in enumerate(handles) if h.uid == uid])
                      for uid in dict.fromkeys(h.uid for h in handles)]  # fmt: skip
            self._motor_groups[joints] = groups
        c, mode = self._c, p.VELOCITY_CONTROL
        for uid, links, places in groups:
            p.setJointMotorControlArray(
                uid, links, mode, targetVelocities=[sign * vels[i] for i, sign in places],
                forces=[fmaxes[i] for i, _ in places], physicsClientId=c,
            )  # fmt: skip

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        uid = self._layout.uid[body]
        pos, quat, lin_vel = self._frames.to_inertial(body, pos, quat, lin_vel, ang_vel)
        p.resetBasePositionAndOrientation(uid, list(pos), xyzw(quat), physicsClientId=self._c)
        p.resetBaseVelocity(uid, list(lin_vel), list(ang_vel), physicsClientId=self._c)
        self._cache = None

    # --- metadata and teardown --------------------------------------------------------------------

    def _imported_model(self) -> ImportedModel:
        return read_imported(p, self._c, self.world, self._layout)

    def _settings(self) -> dict[str, Any]:
        engine = dict(p.getPhysicsEngineParameters(physicsClientId=self._c))
        out: dict[str, Any] = {
            "mode": "DIRECT",
            "fixed_time_step": self._h,
            "substeps": self.world.substeps,
            "num_sub_steps": 0,
            "solver_iterations": self._iterations,
            "stack_height": self._stack,
            "deterministic_overlapping_pairs": self.options.deterministic_overlapping_pairs,
            "restitution_velocity_threshold": self._threshold,
            "bounce_vel": self._fit.restitution_threshold,
            "contact_breaking_threshold": CONTACT_BREAKING_THRESHOLD,
            "impact_contact_erp": "0 for a substep in which a bouncing pair is hit, else Bullet's 0.08"
            if self._impacts.active
            else "Bullet's (no pair bounces)",
            "plane": f"static box, half size {PLANE_HALF_SIZE:g} m, top face on the plane",
            "damping": 0.0,
            "sleeping": "disabled",
            "friction_clamp": FRICTION_CLAMP,
            "surface_mapping": self._fit.method,
            "engine_parameters": engine,
        }
        if self._fit.threshold_note:
            out["restitution_velocity_threshold_note"] = self._fit.threshold_note
        if self._fit.method != "sqrt":
            names = [b.name for b in self.world.bodies]
            out["restitution_per_body"] = dict(zip(names, self._fit.restitution, strict=True))
            out["lateral_friction_per_body"] = dict(zip(names, self._fit.friction, strict=True))
        return out

    def _close(self) -> None:
        c, self._c = self._c, -1
        self._cache, self._listed = None, None
        if p.isConnected(physicsClientId=c):
            p.disconnect(physicsClientId=c)
