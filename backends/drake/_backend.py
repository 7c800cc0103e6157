"""The Drake backend: the contract of backends/base.py on the MultibodyPlant that ``_build`` makes.

One scenario step is ``world.substeps`` discrete plant updates of ``dt / substeps``
(``Diagram.ExecuteForcedEvents``: exactly one update each; the context's time is set by hand). Before the
step: the one-step forces and the kinematic bodies' weight compensation go into the applied spatial
force port (a fixed value persists, so it is refixed every step), the motors' target rates into the
desired-state port (Kp 0); before each update the kinematic bodies get their pose and velocity. After each: the
contacts Drake used (its sampled ContactResults: computed at the step's start poses, as ODE collides before
stepping) and the motors' net actuation. docs/backends/drake.md has the mapping and its measured limits.
"""

from __future__ import annotations

import logging
import math
from typing import Any, ClassVar

import numpy as np
from pydrake.multibody.math import SpatialForce, SpatialVelocity
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.multibody.tree import PdControllerGains, default_model_instance

from .._kit import BackendOptions, KinematicPose, SubstepContacts, SubstepMean, group_by_pair, substep_times
from .._kit.stacks import free_bodies, stack_height
from ..base import Backend
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
from ._build import JointHandle, _transform, build, check_hulls, vec
from ._build import check as check_build
from ._imported import read_imported
from ._options import DrakeOptions, check_stack
from ._points import read_points
from ._reactions import Reactions


class _NoDeformableNotice(logging.Filter):
    """Drop Drake's notice that rigid half spaces get no deformable contact (printed at every build with a
    plane; this adapter makes no deformable bodies, so it says nothing about the run)."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "not currently supported for deformable contact" not in record.getMessage()


logging.getLogger("drake").addFilter(_NoDeformableNotice())

#: The effort limit of a motor that is off (``fmax`` 0): Drake needs a limit > 0, and the PD force is clamped to
#: it, so the motor applies at most this many newtons (or N m).
MOTOR_OFF = 1e-30


class DrakeBackend(Backend):
    """Drake's MultibodyPlant with ODE semantics (docs/backends/drake.md)."""

    name: ClassVar[str] = "drake"
    engine_distribution: ClassVar[str] = "drake"
    precision: ClassVar[Precision] = Precision.FLOAT64  # Eigen doubles
    #: no contact:bounce (Drake has no restitution coefficient, only dissipation: refused up front); no
    #: shape:trimesh. Convex hulls are compliant hydroelastic ``Convex`` geometries (a 0.3 x 0.2 x 0.1 hull box
    #: rests 0.25 mm deep, the elastic foundation's m g c / (E A)); with ``contact_model: point`` they are
    #: refused (``check_world``: one contact point per hull pair, docs/backends/drake.md). Armature is the joint
    #: actuator's rotor inertia, stiffness a joint spring force element (``_joint_dynamics``).
    capabilities: ClassVar[frozenset[Capability]] = (
        RIGID_BODY_CAPABILITIES | (ROBOT_CAPABILITIES - {Capability.SHAPE_TRIMESH})
    ) - {Capability.CONTACT_BOUNCE} | {Capability.JOINT_REACTION, Capability.CONTACT_POINTS, Capability.JOINT_MIMIC,
                                       Capability.JOINT_ARMATURE, Capability.JOINT_STIFFNESS}  # fmt: skip
    Options: ClassVar[type[BackendOptions]] = DrakeOptions
    #: pybind11 turns Drake's C++ exceptions (std::exception, DRAKE_THROW_UNLESS) into RuntimeError.
    engine_errors: ClassVar[tuple[type[BaseException], ...]] = (RuntimeError,)
    options: DrakeOptions

    @classmethod
    def check_world(cls, world: CompiledWorld, options: BackendOptions) -> None:
        check_build(world)  # a loop of joints, a pair's mu the geometries cannot combine to, ... (no engine)
        check_hulls(world, options)
        check_stack(stack_height(free_bodies(world)))

    def _build(self) -> None:
        world = self.world
        self._h = world.dt / world.substeps
        self._engine_steps = 0
        self._hydroelastic = self.options.contact_model != "point"
        self._times = substep_times(world.dt, world.substeps)
        built = build(world, self.options, self._h)
        self._built = built
        self._plant = plant = built.plant
        self._diagram = built.diagram
        self._context = self._diagram.CreateDefaultContext()
        self._pc = plant.GetMyMutableContextFromRoot(self._context)
        self._sg_context = built.scene_graph.GetMyContextFromRoot(self._context)
        self._query_port = built.scene_graph.get_query_output_port()
        self._bodies = built.bodies
        self._joints: list[JointHandle] = built.joints
        self._body_index = [b.index() if b is not None else None for b in built.bodies]
        self._force_port = plant.get_applied_spatial_force_input_port()
        self._contact_port = plant.get_contact_results_output_port()
        self._actuation_port = plant.get_net_actuation_output_port()
        self._pose_port = plant.get_body_poses_output_port()
        self._velocity_port = plant.get_body_spatial_velocities_output_port()
        self._actuated = built.actuated
        self._desired_port = plant.get_desired_state_input_port(default_model_instance())
        self._targets = np.zeros(len(self._actuated))
        self._motor_slot = {j: k for k, j in enumerate(self._actuated)}
        self._motor_sign = np.array([self._joints[j].sign for j in self._actuated])
        self._motor_mean = SubstepMean(len(self._actuated))
        self._substep_contacts = SubstepContacts(world.substeps)
        self._kinematic_weight = [
            (i, self._bodies[i].default_mass()) for i, b in enumerate(world.bodies) if b.motion is Motion.KINEMATIC
        ]
        self._static = [i for i, b in enumerate(world.bodies) if b.motion is Motion.STATIC]
        self._prev_quat = np.array([b.quat for b in world.bodies], dtype=float).reshape(-1, 4)
        rated = (JointKind.SLIDER, JointKind.HINGE)
        self._coordinates = [(j, h) for j, h in enumerate(self._joints) if h.spec.kind in rated]
        self._contacts_now: list[Contact] = []
        self._points_now: list[ContactPoint] = []
        watched = [[j.name for j in world.joints].index(name) for name in world.reaction_joints]
        self._reactions = Reactions(plant, self._pc, self._joints, watched) if watched else None
        self._reaction_mean = SubstepMean(6 * len(watched))
        for i, body in enumerate(world.bodies):
            if body.motion is not Motion.STATIC and self._free(i):
                plant.SetFreeBodyPose(self._pc, self._bodies[i], _transform(body.pos, body.quat))
                self._set_velocity(i, body.lin_vel, body.ang_vel)
        self._initial_joint_rates()
        for j, handle in enumerate(self._joints):
            if handle.actuator is not None:
                motor = handle.spec.motor
                self._set_motor(j, motor.vel if motor else 0.0, motor.fmax if motor else 0.0)
        for i, pose in self.kinematic.items():
            self._put(i, pose, 0.0)
        self._forces([])

    def _free(self, i: int) -> bool:
        return bool(self._bodies[i].is_floating_base_body()) if self._bodies[i] is not None else False

    def _imported_model(self) -> ImportedModel:
        return read_imported(self.world, self._built, self._pc)

    def _settings(self) -> dict[str, Any]:
        o = self.options
        names = [b.name for b in self.world.bodies]
        return {
            "engine_dt": self._h,
            "engine_steps_per_step": self.world.substeps,
            "contact_model": o.contact_model,
            "discrete_contact_approximation": o.approximation,
            "penetration_allowance": o.penetration_allowance,
            "hydroelastic_modulus": o.hydroelastic_modulus,
            "motors": f"PD actuators, Kp 0, Kd {o.motor_gain:g}, effort limit fmax (clamped in the solve)",
            "kinematic": "free bodies 1e6 x the heaviest dynamic body, weight cancelled, pose and velocity imposed",
            "friction_per_body": dict(zip(names, self._built.friction, strict=True)),
        }

    # --- inputs ---------------------------------------------------------------------------------------

    def _set_motor(self, joint: int, vel: float, fmax: float) -> None:
        handle = self._joints[joint]
        handle.actuator.set_effort_limit(max(float(fmax), MOTOR_OFF))
        # off: Kd 0 as well (with Kd 1e7 SAP's regularised clamp still leaks 0.01 N through a 1e-30 N limit)
        handle.actuator.set_controller_gains(PdControllerGains(p=0.0, d=self.options.motor_gain if fmax > 0 else 0.0))
        self._targets[self._motor_slot[joint]] = handle.sign * vel

    def _place_kinematic(self, body: int, pose: KinematicPose) -> None:
        self._put(body, pose, 0.0)

    def _reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self._plant.SetFreeBodyPose(self._pc, self._bodies[body], _transform(pos, quat))
        self._set_velocity(body, lin_vel, ang_vel)
        self._prev_quat[body] = quat

    def _put(self, body: int, pose: KinematicPose, t: float) -> None:
        pos, quat = pose.at(t)
        self._plant.SetFreeBodyPose(self._pc, self._bodies[body], _transform(pos, quat))
        self._set_velocity(body, pose.lin_vel, pose.ang_vel)

    def _set_velocity(self, body: int, lin: Vec3, ang: Vec3) -> None:
        """A free body's velocity: its body frame origin's, in the world frame (Drake's V_WB)."""
        velocity = SpatialVelocity(vec(ang), vec(lin))
        self._plant.SetFreeBodySpatialVelocity(self._pc, self._bodies[body], velocity)

    def _initial_joint_rates(self) -> None:
        """A jointed body's initial velocity relative to its parent's, along its joint's axis."""
        bodies = {b.name: b for b in self.world.bodies}
        for handle in self._joints:
            spec = handle.spec
            child = bodies[spec.body]
            parent = bodies[spec.other] if spec.other is not None else None
            lin = np.subtract(child.lin_vel, parent.lin_vel if parent else (0.0, 0.0, 0.0))
            ang = np.subtract(child.ang_vel, parent.ang_vel if parent else (0.0, 0.0, 0.0))
            if spec.kind is JointKind.SLIDER:
                handle.joint.set_translation_rate(self._pc, handle.sign * float(np.dot(lin, spec.axis)))
            elif spec.kind is JointKind.HINGE:
                handle.joint.set_angular_rate(self._pc, handle.sign * float(np.dot(ang, spec.axis)))

    def _forces(self, extra: list[Any]) -> None:
        self._force_port.FixValue(self._pc, extra)

    def _applied(self) -> list[Any]:
        """The step's spatial forces: the one-step forces at each COM and the kinematic bodies' lift."""
        out = []
        g = vec(self.world.gravity)
        for i, acc in self.forces.items():
            out.append(self._spatial(i, acc[:3], acc[3:]))
        for i, mass in self._kinematic_weight:
            out.append(self._spatial(i, -mass * g, np.zeros(3)))
        return out

    def _spatial(self, i: int, force: Any, torque: Any) -> Any:
        f = ExternallyAppliedSpatialForce()
        f.body_index = self._body_index[i]
        f.p_BoBq_B = vec(self.world.bodies[i].com)
        f.F_Bq_W = SpatialForce(vec(torque), vec(force))
        return f

    # --- stepping -------------------------------------------------------------------------------------

    def _step(self) -> None:
        n = self.world.substeps
        self._forces(self._applied())  # refixed every step: a force lasts one
        if self._actuated:
            self._desired_port.FixValue(self._pc, np.concatenate([np.zeros(len(self._actuated)), self._targets]))
            self._motor_mean.start()
        self._substep_contacts.start()
        if self._reactions is not None:
            self._reaction_mean.start()
        for k in range(n):
            if k:
                for i, pose in self.kinematic.items():
                    self._put(i, pose, self._times[k - 1])
            deepest = self._penetrations() if self._hydroelastic else None
            if self._reactions is not None:
                self._reactions.before()
            # one discrete plant update of exactly h (Simulator.AdvanceTo's event times drift by rounding)
            self._diagram.ExecuteForcedEvents(self._context, publish=False)
            self._engine_steps += 1
            self._context.SetTime(self._engine_steps * self._h)
            if self._actuated:
                self._motor_mean.add(self._actuation_port.Eval(self._pc) * self._motor_sign)
            self._substep_contacts.add(self._read_contacts(deepest))
            if k == n - 1 and self.world.contact_points:
                self._points_now = read_points(self._contact_port.Eval(self._pc), self._built.geometry_body, deepest)
            if self._reactions is not None:
                self._reaction_mean.add(self._reactions.read().ravel())
        if self._actuated:
            self._motor_mean.finish()
        if self._reactions is not None:
            self._reaction_mean.finish()
        dt = self.world.dt
        for i, pose in self.kinematic.items():
            self._put(i, KinematicPose(*pose.at(dt), pose.lin_vel, pose.ang_vel), 0.0)
        self._contacts_now = self._substep_contacts.merged()

    def _penetrations(self) -> dict[tuple[int, int], float]:
        """The deepest penetration per body pair at the poses the coming step starts from (hydroelastic
        contacts carry a pressure field, not a depth: SceneGraph's point-pair query measures it)."""
        query = self._query_port.Eval(self._sg_context)
        owner = self._built.geometry_body
        out: dict[tuple[int, int], float] = {}
        for pair in query.ComputePointPairPenetration():
            a, b = owner[pair.id_A.get_value()], owner[pair.id_B.get_value()]
            key = (min(a, b), max(a, b))
            out[key] = max(out.get(key, 0.0), float(pair.depth))
        return out

    def _read_contacts(self, deepest: dict[tuple[int, int], float] | None = None) -> list[Contact]:
        results = self._contact_port.Eval(self._pc)
        owner = self._built.geometry_body
        first, second, depth, force = [], [], [], []
        for k in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(k)
            pair = info.point_pair()
            first.append(owner[pair.id_A.get_value()])
            second.append(owner[pair.id_B.get_value()])
            depth.append(float(pair.depth))
            force.append(abs(float(np.dot(info.contact_force(), pair.nhat_BA_W))))
        for k in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(k)
            surface = info.contact_surface()
            first.append(owner[surface.id_M().get_value()])
            second.append(owner[surface.id_N().get_value()])
            a, b = first[-1], second[-1]
            depth.append((deepest or {}).get((min(a, b), max(a, b)), math.nan))
            normal = _mean_normal(surface)
            force.append(abs(float(np.dot(info.F_Ac_W().translational(), normal))))
        return group_by_pair(len(self.world.bodies), first, second, depth, force)

    # --- outputs --------------------------------------------------------------------------------------

    def _body_states(self) -> BodyStates:
        n = len(self.world.bodies)
        pos, quat = np.empty((n, 3)), np.empty((n, 4))
        lin, ang = np.zeros((n, 3)), np.zeros((n, 3))
        poses = self._pose_port.Eval(self._pc)
        velocities = self._velocity_port.Eval(self._pc)
        for i, index in enumerate(self._body_index):
            if index is None:
                spec = self.world.bodies[i]
                pos[i], quat[i] = spec.pos, spec.quat
                continue
            x = poses[int(index)]
            pos[i] = x.translation()
            q = x.rotation().ToQuaternion()
            quat[i] = (q.w(), q.x(), q.y(), q.z())
            v = velocities[int(index)]
            lin[i], ang[i] = v.translational(), v.rotational()
        flip = np.einsum("ij,ij->i", quat, self._prev_quat) < 0.0
        if flip.any():
            quat[flip] *= -1.0
        self._prev_quat = quat.copy()
        return BodyStates(pos, quat, lin, ang)

    def _joint_states(self) -> JointStates:
        m = len(self._joints)
        position, velocity, force = np.full(m, math.nan), np.full(m, math.nan), np.zeros(m)
        for j, handle in self._coordinates:
            if handle.spec.kind is JointKind.SLIDER:
                q, v = handle.joint.get_translation(self._pc), handle.joint.get_translation_rate(self._pc)
            else:
                q, v = handle.joint.get_angle(self._pc), handle.joint.get_angular_rate(self._pc)
            position[j], velocity[j] = handle.sign * q, handle.sign * v
        if self._actuated:
            force[self._actuated] = self._motor_mean.mean
        return JointStates(position, velocity, force)

    def _joint_reactions(self) -> np.ndarray:
        return self._reaction_mean.mean.reshape(-1, 6).copy()

    def _contact_points(self) -> list[ContactPoint]:
        return list(self._points_now)

    def _contacts(self) -> list[Contact]:
        return list(self._contacts_now)

    def _close(self) -> None:
        self._context = None



def _mean_normal(surface: Any) -> np.ndarray:
    """The area-weighted normal of a hydroelastic contact surface (unit)."""
    total = np.zeros(3)
    for f in range(surface.num_faces()):
        total += surface.area(f) * np.asarray(surface.face_normal(f))
    norm = float(np.linalg.norm(total))
    return total / norm if norm > 0.0 else total
