"""The DART (dartpy) backend: the contract of backends/base.py on top of the world of ``_build``.

DART resets joint commands and external forces in every ``World.step()``, so each engine step re-issues
the motor targets (SERVO actuators, force-limited to +-fmax), the kinematic velocities (VELOCITY
actuators on FreeJoints) and the one-step forces of the scenario step. Poses of free bodies are read in
two calls per pair of skeletons (``_reads``; FreeJoint positions are [rotation vector, translation],
velocities [angular, linear], both in the world frame) and converted with numpy: DART's per-body reads cost
several times the other engines' (notes §9).
"""

from __future__ import annotations

import math
from functools import partial
from typing import Any, ClassVar

import dartpy as dart
import numpy as np

from .._kit import BackendOptions, KinematicPose, SubstepContacts, SubstepMean
from ..base import Backend
from ..errors import UnsupportedFeature
from ..types import (
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
from . import _contacts, _surfaces
from ._armature import add_armature, check_armature, hold_armature
from ._build import BodyHandle, JointHandle, build, place_free
from ._build import check as check_build
from ._friction import friction_model
from ._gate import BounceGate
from ._impacts import ArmatureImpacts
from ._imported import read_imported
from ._mimic import Mimics, check_mimics
from ._options import DartOptions
from ._reactions import Reactions
from ._reads import com_motion, rotvec_to_quat, row_index, state_readers

_NAME = "dart"


class DartBackend(Backend):
    name: ClassVar[str] = _NAME
    engine_distribution: ClassVar[str] = "dartpy"
    precision: ClassVar[Precision] = Precision.FLOAT64  # Eigen doubles throughout
    #: Every robot capability: compound bodies, COM offsets, convex hulls and static triangle meshes (both as
    #: DART MeshShapes, ``_meshes``), excluded pairs (the solver's BodyNodeCollisionFilter).
    #: stiffness: DART's own joint spring (_build). Not armature: DART 6.20 has none, and a rotor held by its
    #: coupler constraint does not reflect it (the constraint's impulse counts the rotor's inertia only: a
    #: wheel at 10 rad/s coupled to an equal rotor at rest swaps rates with it each step, instead of 5 and 5)
    capabilities: ClassVar[frozenset[Capability]] = (
        RIGID_BODY_CAPABILITIES
        | ROBOT_CAPABILITIES
        | {Capability.CONTACT_POINTS, Capability.JOINT_STIFFNESS}
        | {Capability.JOINT_ARMATURE}  # in DART's implicit joint inertia (_armature)
        | {Capability.JOINT_REACTION}  # getWrenchToChildBodyNode
        | {Capability.JOINT_MIMIC}  # DART's coupler with the offset that makes its row exact (_mimic)
    )
    Options: ClassVar[type[BackendOptions]] = DartOptions
    #: joint damping is DART's own (GenericJoint's damping coefficient, integrated implicitly): DART's servo
    #: constraint drops a bound as small as damping x a slow rate (docs/semantics.md, "Joint dynamics")
    native_damping: ClassVar[bool] = True
    #: pybind11 turns the C++ exceptions of DART into RuntimeError (DART 6 itself mostly prints its errors,
    #: dterr, and carries on); Python's own RuntimeError subclasses are never translated (backends.errors).
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = (RuntimeError,)
    options: DartOptions

    @classmethod
    def engine_label(cls) -> str:
        engine, wrapper = str(dart.__version__), cls.engine_version()
        return f"DART {engine}" + ("" if wrapper == engine else f" (dartpy {wrapper})")

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        if isinstance(options, DartOptions):
            friction_model(world, options.friction)  # `friction: cone` above the solver's mu is refused
        check_build(world)  # the joint trees: loops, joint kinds, planes (no engine call)
        check_armature(world)  # armature with a motor or friction loss (DART's servo does not see it)
        check_mimics(world)  # one coupling per joint tree, no motor on a follower (_mimic)

    def _build(self) -> None:
        world = self.world
        self._detector = self.options.collision_detector
        self._engine_steps = world.substeps * _split(world.dt / world.substeps, self.options.max_engine_dt)
        try:
            coefficients, self._surface_conflict = _surfaces.solve(world), ""
        except UnsupportedFeature as exc:  # no fixed values exist: solve for the touching pairs each step
            coefficients, self._surface_conflict = _surfaces.solve(world, []), str(exc)
        self._friction = friction_model(world, self.options.friction)
        built = build(world, self._detector, coefficients, self._engine_steps, self._friction)
        self._dart: Any = built.world
        self._bodies: list[BodyHandle] = built.bodies
        self._joints: list[JointHandle] = built.joints
        self._armature = add_armature(built.joints, world.dt / self._engine_steps)
        self._mimics = Mimics(world, built.joints)
        moving = [h.skeleton for h, b in zip(self._bodies, world.bodies, strict=True) if b.motion is not Motion.STATIC]
        self._impacts = ArmatureImpacts({id(s): s for s in moving}.values(), built.joints)
        self._coefficients = built.coefficients
        self._free = [i for i, h in enumerate(self._bodies) if h.free]
        self._free_at = row_index(self._free)
        self._read_q, self._read_v = state_readers([self._bodies[i].skeleton for i in self._free])
        self._static = [i for i, b in enumerate(world.bodies) if b.motion is Motion.STATIC]
        self._static_at = row_index(self._static)
        self._reader = _contacts.ContactReader(len(world.bodies), self._static)
        self._com_motion = partial(com_motion, world.bodies, self._bodies)  # for the approach speeds
        self._linked = [i for i in range(len(world.bodies)) if i not in set(self._free) | set(self._static)]
        coordinate = (JointKind.SLIDER, JointKind.HINGE)
        self._coordinates = [(j, h.joint, h.sign) for j, h in enumerate(self._joints) if h.spec.kind in coordinate]
        self._servos: list[tuple[int, JointHandle]] = []
        self._static_pos = np.array([world.bodies[i].pos for i in self._static], dtype=float).reshape(-1, 3)
        self._static_quat = np.array([world.bodies[i].quat for i in self._static], dtype=float).reshape(-1, 4)
        self._prev_quat = np.array([b.quat for b in world.bodies], dtype=float).reshape(-1, 4)
        self._motor_mean = SubstepMean(len(self._joints))
        self._reactions = Reactions(self.world, self._bodies, self._joints)
        self._reaction_mean = SubstepMean(6 * len(self._reactions))
        self._substep_contacts = SubstepContacts(self._engine_steps)
        self._relevant = set(_surfaces.touching_pairs(world))
        self._touching: list[tuple[int, int]] | None = None
        self._thresholds = _surfaces.thresholded_pairs(world)  # pairs whose bounce_vel the adapter applies
        self._plastic: frozenset[tuple[int, int]] = frozenset()
        self._fixed_applied = not self._surface_conflict  # the shapes hold the build's values (every pair's surface)
        # engine steps in which no contact can bounce leave the bounce_vel pass out (``_gate``)
        self._gate = BounceGate(world, self._free, usable=not self._surface_conflict and bool(self._thresholds))
        self._velocities: np.ndarray | None = None  # the free bodies' (N, 6) velocities, while still current
        for j, handle in enumerate(self._joints):
            if handle.spec.motor is not None:
                self._set_motor(j, handle.spec.motor.vel, handle.spec.motor.fmax)

    def _imported_model(self) -> ImportedModel:
        armature = {joint.getName(): extra for joint, extra, _ in self._armature}
        return read_imported(self.world, self._bodies, self._joints, armature)

    def _settings(self) -> dict[str, Any]:
        names = [b.name for b in self.world.bodies]
        return {
            "collision_detector": self._detector,
            "engine_dt": self.world.dt / self._engine_steps,
            "engine_steps_per_step": self._engine_steps,
            "constraint_solver": "BoxedLcpConstraintSolver ("
            + ("NsgsFrictionSolver, Coulomb cone" if self._friction == "cone" else "Dantzig, friction pyramid")
            + ", PGS fallback)",
            "friction": self._friction,
            "deactivation": False,
            "mu_inf_as": _surfaces.finite_mu(self.world),
            "surfaces": "per step, for the touching pairs" if self._surface_conflict else "fixed per shape",
            "friction_per_body": dict(zip(names, self._coefficients.friction, strict=True)),
            "restitution_per_body": dict(zip(names, self._coefficients.restitution, strict=True)),
        }

    # --- inputs ---------------------------------------------------------------------------------------

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        handle = self._joints[joint]
        handle.vel, handle.fmax = float(vel), max(0.0, float(fmax))
        if handle.fmax > 0.0:
            handle.joint.setActuatorType(dart.dynamics.ActuatorType.SERVO)
            handle.joint.setForceLowerLimit(0, -handle.fmax)
            handle.joint.setForceUpperLimit(0, handle.fmax)
        else:
            handle.joint.setActuatorType(dart.dynamics.ActuatorType.PASSIVE)
        self._servos = [(j, h) for j, h in enumerate(self._joints) if h.fmax > 0.0]

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        place_free(self._bodies[body].root, pose.pos, pose.quat, pose.lin_vel, pose.ang_vel)
        self._prev_quat[body] = pose.quat
        self._velocities = None

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        place_free(self._bodies[body].root, pos, quat, lin_vel, ang_vel)
        self._prev_quat[body] = quat
        self._velocities = None

    # --- stepping -------------------------------------------------------------------------------------

    def _step(self) -> None:
        servos, n = self._servos, self._engine_steps
        h = self.world.dt / n
        self._motor_mean.start()
        if self._reactions:
            self._reaction_mean.start()
        self._substep_contacts.start()
        for _ in range(n):
            # World.step() clears commands and external forces: re-issue them for every engine step.
            if self._surface_conflict or self._thresholds:
                self._match_touching_pairs(quiet=not self._surface_conflict and self._quiet(h))
            self._impacts.before()
            self._mimics.step(self._dart, self._issue_inputs, h)
            self._impacts.after(h, self._touching_skeletons)
            self._velocities = None
            applied = np.zeros(len(self._joints))
            for j, handle in servos:
                applied[j] = handle.sign * handle.joint.getConstraintImpulse(0) / h
            self._motor_mean.add(applied)
            if self._reactions:
                self._reaction_mean.add(self._reactions.now())
            if n > 1:
                self._substep_contacts.add(self._reader.contacts(self._dart.getLastCollisionResult().getContacts()))
        self._motor_mean.finish()
        if self._reactions:
            self._reaction_mean.finish()
        dt = self.world.dt
        for i, pose in self.kinematic.items():
            pos, quat = pose.at(dt)
            place_free(self._bodies[i].root, pos, quat, pose.lin_vel, pose.ang_vel)

    def _touching_skeletons(self) -> list[tuple[str, str]]:
        """The pairs of skeletons (by name) in contact in the last engine step."""
        name = [h.skeleton.getName() for h in self._bodies]
        pairs = self._reader.pairs(self._dart.getLastCollisionResult().getContacts())
        return [(name[a], name[b]) for a, b in pairs]

    def _issue_inputs(self) -> None:
        """The step's commands, forces and armature torques (World.step() clears them)."""
        for _, handle in self._servos:
            handle.joint.setCommand(0, handle.sign * handle.vel)
        for i, pose in self.kinematic.items():
            self._bodies[i].root.setCommands(np.concatenate([pose.ang_vel, pose.lin_vel]))
        for i, acc in self.forces.items():
            body = self._bodies[i]
            if body.com is None:
                body.node.addExtForce(acc[:3])
            else:  # at the centre of mass (an offset in the body frame), the force in the world frame
                body.node.addExtForce(acc[:3], body.com, False, True)
            body.node.addExtTorque(acc[3:])
        hold_armature(self._armature)

    def _joint_reactions(self) -> np.ndarray:
        return self._reaction_mean.mean.reshape(-1, 6).copy()

    # --- outputs --------------------------------------------------------------------------------------

    def _body_states(self) -> BodyStates:
        n = len(self._bodies)
        pos, quat = np.empty((n, 3)), np.empty((n, 4))
        lin, ang = np.zeros((n, 3)), np.zeros((n, 3))
        if self._free:
            q = np.concatenate([read() for read in self._read_q]).reshape(-1, 6)
            v = self._velocities = np.concatenate([read() for read in self._read_v]).reshape(-1, 6)
            free = self._free_at
            pos[free], quat[free] = q[:, 3:], rotvec_to_quat(q[:, :3])
            ang[free], lin[free] = v[:, :3], v[:, 3:]
        for i in self._linked:
            node = self._bodies[i].node
            transform = node.getWorldTransform()
            pos[i], quat[i] = transform.translation(), transform.quaternion().wxyz()
            lin[i], ang[i] = node.getLinearVelocity(), node.getAngularVelocity()
        if self._static:
            pos[self._static_at], quat[self._static_at] = self._static_pos, self._static_quat
        # q and -q are one rotation: keep the sign continuous, as ODE's integrated quaternion is.
        flip = np.einsum("ij,ij->i", quat, self._prev_quat) < 0.0
        if flip.any():
            quat[flip] *= -1.0
        self._prev_quat = quat.copy()
        return BodyStates(pos, quat, lin, ang)

    def _joint_states(self) -> JointStates:
        m = len(self._joints)
        position, velocity = np.full(m, math.nan), np.full(m, math.nan)
        for j, joint, sign in self._coordinates:
            position[j] = sign * joint.getPosition(0)
            velocity[j] = sign * joint.getVelocity(0)
        return JointStates(position, velocity, self._motor_mean.mean.copy())

    def _contacts(self) -> list[Contact]:
        if self._engine_steps > 1:
            return self._substep_contacts.merged() if self.steps else []
        return self._reader.contacts(self._dart.getLastCollisionResult().getContacts())

    def _contact_points(self) -> list[ContactPoint]:
        return self._reader.points(self._dart.getLastCollisionResult().getContacts()) if self.steps else []

    def _quiet(self, h: float) -> bool:
        """Whether no contact of the coming engine step (``h`` long) can bounce, so that the bounce_vel pass
        changes nothing in it (``_gate``)."""
        if not self._gate.usable or self.forces:
            return False
        if self._velocities is None:
            self._velocities = np.concatenate([read() for read in self._read_v]).reshape(-1, 6)
        return self._gate.quiet(self._velocities, h)

    def _match_touching_pairs(self, quiet: bool = False) -> None:
        """Give the pairs about to touch their surfaces (worlds whose pairs have no fixed solution).

        DART's step detects collisions at the current poses; detecting them here first tells which pairs
        its contact constraints will combine, so per-shape values are solved for those pairs only.

        With ``bounce_vel`` (worlds with thresholded pairs): DART has no threshold of its own but 0.1 m/s on
        e*v, so a touching pair approaching no faster than its ``bounce_vel`` before the step (ODE's test)
        gets bounce 0 for the step (``plastic``). When per-shape values cannot give it that together with
        the other touching pairs, the pair keeps its bounce (docs/backends/dart.md).

        ``quiet``: no contact can bounce in the coming engine step (``_gate``), so the shapes take the build's
        values and the contacts are not read. The collision query itself still runs: DART's ODE detector
        keeps a contact history per pair that every query with a result updates and that supplements later
        queries' contacts, DART's step's own included, so leaving it out changes the step's contacts
        (measured: 44 points instead of 40 two steps later on a pile, and every state after).
        """
        solver = self._dart.getConstraintSolver()
        result = dart.collision.CollisionResult()
        solver.getCollisionGroup().collide(solver.getCollisionOption(), result)
        if quiet:
            self._restore_fixed()
            return
        points = result.getContacts()
        touching = sorted(self._reader.pairs(points) & self._relevant)
        plastic: frozenset[tuple[int, int]] = frozenset()
        if self._thresholds:
            limits = self._thresholds
            speeds = self._reader.approach(points, self._com_motion)
            plastic = frozenset(p for p, v in speeds.items() if p in limits and v <= limits[p])
        if touching == self._touching and plastic == self._plastic:
            return
        pairs = touching if self._surface_conflict or plastic else None
        if pairs is None and self._fixed_applied:  # solve(world) again: the values the shapes already hold
            self._touching, self._plastic = touching, plastic
            return
        try:
            coefficients = _surfaces.solve(self.world, pairs, plastic)
        except UnsupportedFeature as exc:
            if not plastic:
                raise UnsupportedFeature(f"{exc} (at t = {self.steps * self.world.dt:.3f} s)") from None
            coefficients = _surfaces.solve(self.world, pairs)
        self._apply(coefficients)
        self._touching, self._plastic, self._fixed_applied = touching, plastic, pairs is None

    def _restore_fixed(self) -> None:
        """Before an engine step whose contacts are not read (``_quiet``): the build's values, which give every
        pair that can touch its friction (those the last pass solved for its touching pairs only may not, for a
        pair that touches now); restitution does not matter in such a step."""
        if not self._fixed_applied:
            self._apply(self._coefficients)
            self._touching, self._plastic, self._fixed_applied = None, frozenset(), True

    def _apply(self, coefficients: _surfaces.ShapeCoefficients) -> None:
        for handle, f, r in zip(self._bodies, coefficients.friction, coefficients.restitution, strict=True):
            for aspect in handle.aspects:
                aspect.setFrictionCoeff(f)
                aspect.setRestitutionCoeff(r)

    def _close(self) -> None:
        self._dart.removeAllSkeletons()


def _split(step: float, longest: float | None) -> int:
    """How many DART steps make one ``step`` no longer than ``backend_options.dart.max_engine_dt``."""
    if longest is None:
        return 1
    return max(1, math.ceil(step / longest - 1e-9))
