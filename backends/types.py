"""Engine-neutral types shared by the runner and every backend.

A :class:`CompiledWorld` is what a backend is built from: every name resolved, every mass and inertia
computed, every pose in the world frame with quaternions in (w, x, y, z) order, every joint frame and
every contact surface per body pair known. Backends never see YAML.

This module holds the compiled world and re-exports the rest of the vocabulary, so that ``backends.types`` is
the one import: ``basic_types`` (vectors, kinds, precision), ``capabilities``, ``joint_specs`` and
``readings`` (states, contacts, the imported model).

Conventions (ODE's, see docs/semantics.md):

* SI units; angles in radians; the world is Z-up and right-handed.
* Box sizes are **full** edge lengths. Capsules and cylinders lie along the body's local z axis;
  ``length`` is the length of the cylindrical part (a capsule's total length is ``length + 2*radius``).
* A plane's normal is the body's local +z; it passes through the body's position. Planes are static.
* Masses and inertias follow ODE's dMassSetBox/Sphere/Capsule/Cylinder: principal moments about the
  centre of mass, in the body frame. Static bodies carry mass 0.
* Slider position: displacement of ``body`` relative to ``other`` along ``axis`` since the start
  (metres). Hinge angle: rotation of ``body`` relative to ``other`` about ``axis`` since the start
  (radians, right-handed). A motor drives that coordinate's rate towards ``vel`` with force (or torque)
  bounded by ``fmax``; ``fmax == 0`` means the motor is off (ODE's dParamVel / dParamFMax).

Robots (URDF and MJCF models, docs/robots.md) add, and every adapter that declares the matching capability
must honour:

* **Body frame and inertial frame** (``body:com-offset``). ``BodySpec.pos``/``quat`` place the *body frame*
  (a URDF link frame). The centre of mass sits at ``BodySpec.com`` in that frame and the principal axes of
  inertia are the body frame rotated by ``BodySpec.inertia_quat``; ``BodySpec.inertia`` holds the
  principal moments about the COM along those axes (``BodySpec.inertia_tensor()`` is the full tensor in
  the body frame). A hand-written body has ``com == 0`` and ``inertia_quat == IDENTITY``: its frame is
  its inertial frame, as in ODE. States are always those of the body frame: ``pos``/``quat`` its pose,
  ``lin_vel`` the velocity of its origin (so it is the rate of ``pos``; an adapter whose engine reports
  the COM velocity adds ``ang_vel x (pos - com_world)``), ``ang_vel`` its angular velocity.
  ``apply_force`` still acts at the COM; ``reset_body``/``set_kinematic`` place the body frame.
* **Compound bodies** (``shape:compound``). A body whose ``shape.kind`` is ``COMPOUND`` collides with the
  shapes of ``BodySpec.shapes`` (each a :class:`PlacedShape` at a pose in the body frame); the tuple may
  be empty (a link that never touches anything). Mass and inertia are given, never derived from them.
* **Convex meshes** (``shape:convex``). ``Shape.mesh`` holds the convex hull's vertices and outward
  triangles in the shape's frame; the adapter collides with exactly that hull (no re-hulling that moves
  vertices, no margin beyond the engine's usual contact tolerance).
* **Triangle meshes** (``shape:trimesh``), only ever on static bodies: ``Shape.mesh`` as it is, not convex.
* **Collision filters** (``collision:exclude-pairs``). ``CompiledWorld.excluded_pairs`` lists body pairs
  that never touch (the URDF convention: a joint's two links; plus the scenario's ``exclude``): no contact
  force and no entry in ``contacts()``. Pairs were chosen over group/mask bits because all four engines
  express them (PyBullet setCollisionFilterPair, MuJoCo ``<contact><exclude>``, DART's
  BodyNodeCollisionFilter black list, ODE's near callback) and bits run out at 16 or 32 groups.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .basic_types import IDENTITY_QUAT, JointKind, Motion, Precision, Quat, Rgba, ShapeKind, Vec3
from .capabilities import (
    ALL_SHAPES,
    MODEL_FILE_CAPABILITIES,
    OUTPUT_CAPABILITIES,
    RIGID_BODY_CAPABILITIES,
    ROBOT_CAPABILITIES,
    SENSING_CAPABILITIES,
    UNMAPPED_CAPABILITIES,
    Capability,
)
from .geometry import quat_matrices
from .joint_specs import NO_DYNAMICS, JointCoupling, JointDynamics, JointSpec, Motor
from .readings import (
    BodyStates,
    Contact,
    ContactPoint,
    ImportedBody,
    ImportedJoint,
    ImportedModel,
    JointStates,
    new_contact,
)

__all__ = [
    "ALL_SHAPES", "IDENTITY_QUAT", "MODEL_FILE_CAPABILITIES", "NO_DYNAMICS", "OUTPUT_CAPABILITIES",
    "RIGID_BODY_CAPABILITIES", "ROBOT_CAPABILITIES", "SENSING_CAPABILITIES", "UNMAPPED_CAPABILITIES", "BodySpec",
    "BodyStates", "Capability", "CompiledWorld", "Contact", "ContactPoint", "Fluid", "ImportedBody", "ImportedJoint",
    "ImportedModel", "JointCoupling", "JointDynamics", "JointKind", "JointSpec", "JointStates", "Mesh", "ModelFile",
    "Motion", "Motor", "PairSurface", "PlacedShape", "Precision", "Quat", "Rgba", "Shape", "ShapeKind", "Surface",
    "Vec3", "new_contact",
]  # fmt: skip


@dataclass(frozen=True)
class Mesh:
    """Triangles in the shape's frame: vertices in metres (scale applied), faces counter-clockwise seen from
    outside (outward normals by the right-hand rule)."""

    vertices: tuple[Vec3, ...]
    faces: tuple[tuple[int, int, int], ...]
    source: str = ""  # the mesh file it came from, for messages and the trace (not a path to open)


@dataclass(frozen=True)
class Shape:
    """A collision shape in its body's frame: a primitive (sizes in metres), a mesh, or a compound."""

    kind: ShapeKind
    size: Vec3 = (0.0, 0.0, 0.0)  # box: full edge lengths
    radius: float = 0.0  # sphere, capsule, cylinder
    length: float = 0.0  # capsule, cylinder: cylindrical part along local z
    mesh: Mesh | None = None  # convex, trimesh


@dataclass(frozen=True)
class PlacedShape:
    """One collision shape of a compound body at a pose in the body frame, with its own colour."""

    shape: Shape
    pos: Vec3 = (0.0, 0.0, 0.0)
    quat: Quat = IDENTITY_QUAT
    color: Rgba | None = None  # None: the body's colour


@dataclass(frozen=True, kw_only=True)
class Surface:
    """ODE contact surface: restitution ``bounce`` above approach speed ``bounce_vel``; Coulomb ``mu``.
    Keyword-only: ``bounce`` and ``mu`` are both floats, and swapped by position they would pass unnoticed."""

    bounce: float = 0.0
    bounce_vel: float = 0.0
    mu: float = math.inf


@dataclass(frozen=True)
class BodySpec:
    """One body of a compiled world, engine-neutral: motion, collision shape(s), mass properties, start state and
    colour."""

    name: str
    motion: Motion
    shape: Shape
    mass: float
    inertia: Vec3  # principal moments about the COM, body frame
    pos: Vec3
    quat: Quat
    lin_vel: Vec3 = (0.0, 0.0, 0.0)
    ang_vel: Vec3 = (0.0, 0.0, 0.0)  # world frame, rad/s
    color: Rgba = (0.7, 0.7, 0.7, 1.0)
    #: shape COMPOUND: the collision shapes in the body frame (may be empty); otherwise ().
    shapes: tuple[PlacedShape, ...] = ()
    com: Vec3 = (0.0, 0.0, 0.0)  # centre of mass in the body frame
    inertia_quat: Quat = IDENTITY_QUAT  # principal axes of inertia: the body frame rotated by this
    #: what is drawn (a model's <visual>s) in the body frame, for the trace's scene only: no engine reads it;
    #: () draws the collision shapes
    visuals: tuple[PlacedShape, ...] = ()

    def inertia_tensor(self) -> np.ndarray:
        """The full inertia tensor about the COM in the body frame: R diag(inertia) R^T."""
        r = quat_matrices(self.inertia_quat)
        return np.asarray(r @ np.diag(self.inertia) @ r.T, dtype=np.float64)

    def placed_shapes(self) -> tuple[PlacedShape, ...]:
        """The body's collision shapes at their local poses (one, at the origin, for a primitive body)."""
        return self.shapes if self.shape.kind is ShapeKind.COMPOUND else (PlacedShape(self.shape),)


@dataclass(frozen=True)
class PairSurface:
    """The contact surface of one pair of bodies, overriding the world's default for it."""

    a: str
    b: str
    surface: Surface


@dataclass(frozen=True)
class Fluid:
    """The medium MuJoCo's inertia-box fluid model puts the world's bodies in (MJCF `<option density viscosity
    wind>`; docs/semantics.md, "Fluid forces"): kg/m^3, Pa s, m/s in the world frame."""

    density: float = 0.0
    viscosity: float = 0.0
    wind: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class ModelFile:
    """A robot whose model file an engine may build from itself (MJCF on MuJoCo): its bodies and joints are
    also in ``CompiledWorld.bodies``/``joints`` (for every other engine, and for the names), listed here in
    the file's own order (MuJoCo's compiled order: body ``i`` of the file is ``bodies[i]``, the world body
    first)."""

    robot: str  # the robot's name: its bodies and joints are `<robot>.<name>`
    path: str  # absolute
    format: str  # mjcf
    pos: Vec3  # where the model's frame is placed
    quat: Quat
    bodies: tuple[str, ...]  # CompiledWorld body names, in the file's body order (the world body first)
    joints: tuple[str, ...]  # CompiledWorld joint names, in the file's joint order
    needs: frozenset[Capability] = frozenset()  # MODEL_FILE_CAPABILITIES the file uses
    #: the joints' start, (CompiledWorld joint name, position from the model's zero, rate), hinges and slides;
    #: the world's bodies and joints are already at that pose (their stops and readings from there)
    start: tuple[tuple[str, float, float], ...] = ()
    #: the file upgraded from MJCF's legacy dialect (docs/robots.md), what the engine reads instead of the file
    #: (its meshes still relative to ``path``), and the files its `<include>`s name (as written, absolute
    #: path); "": the file as it is
    xml: str = ""
    includes: tuple[tuple[str, str], ...] = ()
    #: (capability, what in the file needs it and where: "model.xml:47: tendon `string`'s length limit"), for
    #: a refusal's message
    need_sites: tuple[tuple[Capability, str], ...] = ()


@dataclass(frozen=True)
class CompiledWorld:
    """What every adapter builds: the bodies, joints, surfaces and settings of one scenario variant, ODE semantics."""

    name: str
    gravity: Vec3
    dt: float  # one scenario step
    substeps: int  # engine steps per scenario step (each dt / substeps long)
    duration: float
    bodies: tuple[BodySpec, ...]
    joints: tuple[JointSpec, ...] = ()
    default_surface: Surface = Surface()
    pair_surfaces: tuple[PairSurface, ...] = ()
    backend_options: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    #: body pairs (names) that never touch: adjacent links of a model and the scenario's exclusions
    excluded_pairs: tuple[tuple[str, str], ...] = ()
    #: robots an engine may build from their model file (MJCF on MuJoCo)
    models: tuple[ModelFile, ...] = ()
    #: joints that move one body together, each group in the file's order (MJCF: several joints in one body):
    #: the same ``body`` and ``other``; joint k+1 turns or slides about its axis as joints 1..k left it
    joint_chains: tuple[tuple[str, ...], ...] = ()
    #: the light bodies an engine's world chains those joints through (backends/_kit/chains.py; none before)
    chain_bodies: frozenset[str] = frozenset()
    #: True: the model file's own options rule (MJCF `<option>`, its geoms' contact parameters, MuJoCo's own
    #: mj_step); the scenario's dt and gravity equal the model's (`world.options: model`, docs/robots.md)
    model_options: bool = False
    #: True: the run reads ``Backend.contact_points()`` (the scenario's ``trace: {contact_points: true}``);
    #: it needs ``contacts:points``
    contact_points: bool = False
    #: the joints whose reaction the scenario reads (``Backend.joint_reactions()`` gives them in this order);
    #: an engine computes and keeps nothing for the others (capability ``joint:reaction``)
    reaction_joints: tuple[str, ...] = ()
    #: joints held at a multiple of another's position (URDF `<mimic>`; capability ``joint:mimic``)
    couplings: tuple[JointCoupling, ...] = ()
    #: the medium every dynamic body with mass is in (an MJCF robot's `<option density viscosity>`; capability
    #: ``world:fluid``); None: none
    fluid: Fluid | None = None

    def body_index(self, name: str) -> int:
        for i, body in enumerate(self.bodies):
            if body.name == name:
                return i
        raise KeyError(name)

    def surface(self, a: str, b: str) -> Surface:
        """The contact surface for bodies ``a`` and ``b`` (a pair override, else the default)."""
        for pair in self.pair_surfaces:
            if {pair.a, pair.b} == {a, b}:
                return pair.surface
        return self.default_surface

    def options_for(self, backend: str) -> Mapping[str, Any]:
        return self.backend_options.get(backend, {})

    def required_capabilities(self) -> frozenset[Capability]:
        need: set[Capability] = set()
        for body in self.bodies:
            need.add(Capability(f"shape:{body.shape.kind.value}"))
            need.update(Capability(f"shape:{p.shape.kind.value}") for p in body.shapes)
            if body.motion is Motion.KINEMATIC:
                need.add(Capability.KINEMATIC)
            if body.com != (0.0, 0.0, 0.0) or body.inertia_quat != IDENTITY_QUAT:
                need.add(Capability.COM_OFFSET)
        if self.excluded_pairs:
            need.add(Capability.COLLISION_FILTER)
        for joint in self.joints:
            need.add(Capability(f"joint:{joint.kind.value}"))
            if joint.other is not None:
                need.add(Capability.JOINT_BETWEEN_BODIES)
            if joint.lo is not None or joint.hi is not None:
                need.add(Capability.JOINT_LIMITS)
            if joint.stop_bounce > 0:
                need.add(Capability.JOINT_STOP_BOUNCE)
            if joint.stop_stiffness is not None or joint.stop_damping is not None:
                need.add(Capability.JOINT_STOP_SOFTNESS)
            if joint.motor is not None or joint.dynamics.dissipative:
                need.add(Capability.JOINT_MOTOR)
            if joint.dynamics.armature > 0:
                need.add(Capability.JOINT_ARMATURE)
            if joint.dynamics.stiffness > 0:
                need.add(Capability.JOINT_STIFFNESS)
        if self.default_surface.bounce > 0 or any(p.surface.bounce > 0 for p in self.pair_surfaces):
            need.add(Capability.CONTACT_BOUNCE)
        if self.substeps > 1:
            need.add(Capability.SUBSTEPS)
        if self.reaction_joints:
            need.add(Capability.JOINT_REACTION)
        if self.joint_chains:
            need.add(Capability.JOINT_SEVERAL_PER_BODY)
        if self.couplings:
            need.add(Capability.JOINT_MIMIC)
        if self.fluid is not None:
            need.add(Capability.WORLD_FLUID)
        for model in self.models:
            need.update(model.needs)
        if self.contact_points:
            need.add(Capability.CONTACT_POINTS)
        return frozenset(need)
