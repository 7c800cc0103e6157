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
from typing import Any, ClassVar

import numpy as np
import pybullet as p

from .._kit import BackendOptions, KinematicPose, SubstepContacts, SubstepMean, substep_times
from .._kit.stacks import stack_height
from ..base import Backend
from ..geometry import IDENTITY
from ..types import (
    RIGID_BODY_CAPABILITIES,
    BodySpec,
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
from ._build import PLANE_HALF_SIZE, Layout, build, xyzw
from ._build import check as check_build
from ._dynamics import set_body_dynamics, set_joint_dynamics
from ._frames import InertialFrames, LinkFrames
from ._impacts import ImpactErp
from ._imported import read_imported
from ._options import PyBulletOptions, check_stack, solver_iterations
from ._reactions import ReactionSensors
from ._reads import ROW, ContactReader, JointReader, base_rows, link_rows
from ._rotors import add_mimics, add_rotors
from ._springs import Springs
from ._surfaces import FRICTION_CLAMP, SurfaceFit, fit_surfaces

_NAME = "pybullet"
#: Bullet keeps contact points up to this distance apart (default 0.02 m). Restitution is lost when a
#: point exists more than about one step before impact [checked: a sphere dropped 0.5 m at dt 0.001
#: rebounds to 0.0000 of its height at 0.02, 0.27 at 0.001]. ODE makes contacts only when touching.
#: NB: Bullet keeps this in a process-wide global, so every instance sets the same value.
CONTACT_BREAKING_THRESHOLD = 0.001
#: restitutionVelocityThreshold = bounce_vel + this * |g| * h (see PyBulletBackend._build_world).
_GRAVITY_MARGIN = 1.5
#: The quaternion's columns in a state row, in (w, x, y, z) order.
_WXYZ = np.array([6, 3, 4, 5])


def _still(body: BodySpec) -> bool:
    """Whether the body's base state reads the same, bit for bit, at every step: a static body whose frame and
    inertial frame are both unturned (Bullet's quaternion-matrix round trip is exact on the identity)."""
    return body.motion is Motion.STATIC and tuple(body.quat) == IDENTITY and tuple(body.inertia_quat) == IDENTITY


def _rows(indices: list[int]) -> slice | list[int]:
    """Row indices as a slice where they are consecutive (a slice assignment is cheaper than an indexed one)."""
    if indices and indices == list(range(indices[0], indices[-1] + 1)):
        return slice(indices[0], indices[-1] + 1)
    return indices


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
        link_bodies = [i for i in range(len(world.bodies)) if self._layout.link[i] >= 0]
        self._frames = InertialFrames(world, links=link_bodies)  # bases' offsets; links' below
        #: per multibody with links: its uid, links and their bodies (and as rows), the links' frame conversion
        self._link_reads = [(uid, links, bodies, _rows(bodies), LinkFrames.of(world, bodies))
                            for uid, links, bodies in self._layout.link_groups]  # fmt: skip
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
        set_body_dynamics(c, world, layout, self._fit, self._frames)
        rates = set_joint_dynamics(c, world, layout, self._set_motor)
        add_rotors(p, c, world, layout, rates)  # joint armature: a rotor geared to the joint (_rotors)
        add_mimics(p, c, world, layout)  # URDF <mimic>: a gear between the two joints (_rotors)
        self._springs = Springs(world, layout)  # joint stiffness: the spring's torque each engine step (_springs)
        bases = [i for i in range(len(world.bodies)) if layout.link[i] < 0]
        # A static base never moves (a mass-0 base that Backend.reset_body refuses and no track moves), but Bullet
        # turns its quaternion into a matrix and back every step, which moves a turned one's by an ulp and back
        # [checked: the friction conformance's incline, 20 degrees: x alternates by 2.8e-17]; unturned, both
        # are exact. So an unturned static base is read once, on the first read, and copied after (the ground
        # and a fixed robot's base: 3 us a step each); every other base is read each time.
        self._static = [i for i in bases if _still(world.bodies[i])]
        moving = [i for i in bases if i not in self._static]
        self._moving_uids = [layout.uid[i] for i in moving]
        self._moving_rows = _rows(moving)
        self._every_body_moves = moving == list(range(len(world.bodies)))  # free bodies only: one read is the array
        self._still: np.ndarray | None = None  # the unturned static bases' rows (others 0), once read
        self._joint_reader = JointReader(len(world.joints), layout)
        self._motor_mean = SubstepMean(len(world.joints))
        self._sensors = ReactionSensors(c, world, layout)  # joint reactions (_reactions)
        self._reaction_mean = SubstepMean(6 * len(self._sensors))
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
        motors = n > 1 and bool(self._joint_reader.one_dof)  # the substeps' motor torques, for their mean
        if n == 1 and not (self.forces or self.kinematic or self._impacts.active or self._sensors or self._springs):
            p.stepSimulation(c)
        else:
            self._step_with_inputs(c, n, motors)
        self._cache = None
        self._listed = None

    def _step_with_inputs(self, c: int, n: int, motors: bool) -> None:
        """The substeps with one-step forces, kinematic bodies, motor torques or contacts to collect."""
        if motors:
            self._motor_mean.start()
        if self._sensors:
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
                self._motor_mean.add(self._joint_reader.motor_torques(c))
            if self._sensors:
                self._reaction_mean.add(self._sensors.now())
            if n > 1:
                self._substep_contacts.add(self._contact_reader(p.getContactPoints(physicsClientId=c)))
        if motors:
            self._motor_mean.finish()
        if self._sensors:
            self._reaction_mean.finish()

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

    # --- reading --------------------------------------------------------------------------------

    def _fresh_rows(self) -> np.ndarray:
        """The bodies' states now (between substeps the cache is stale)."""
        self._cache = None
        return self._read()

    def _read(self) -> np.ndarray:
        if self._cache is not None:
            return self._cache
        c = self._c
        if self._every_body_moves:
            arr = base_rows(c, self._moving_uids)
        else:  # static bases, or links of jointed trees
            if self._still is None:
                self._still = np.zeros((len(self.world.bodies), ROW))
                self._still[self._static] = base_rows(c, [self._layout.uid[i] for i in self._static])
            arr = self._still.copy()
            if self._moving_uids:
                arr[self._moving_rows] = base_rows(c, self._moving_uids)
            for uid, links, _, rows, frames in self._link_reads:
                arr[rows] = link_rows(c, uid, links, frames)
        self._frames.to_body(arr)  # the bases' inertial frames -> body frames
        self._cache = arr
        return arr

    def _body_states(self) -> BodyStates:
        arr = self._read()
        return BodyStates(
            pos=arr[:, 0:3].copy(),
            quat=arr.take(_WXYZ, axis=1),  # x, y, z, w -> w, x, y, z
            lin_vel=arr[:, 7:10].copy(),
            ang_vel=arr[:, 10:13].copy(),
        )

    def _joint_states(self) -> JointStates:
        pos, vel, force = self._joint_reader.states(self._c)
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
