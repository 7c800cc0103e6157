"""Engine-neutral types shared by the runner and every backend.

A :class:`CompiledWorld` is what a backend is built from: every name resolved, every mass and inertia
computed, every pose in the world frame with quaternions in (w, x, y, z) order, every joint frame and
every contact surface per body pair known. Backends never see YAML.

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

import enum
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import partial
from typing import Any, NamedTuple

import numpy as np

from .geometry import quat_matrices

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # (w, x, y, z)
Rgba = tuple[float, float, float, float]


class Motion(str, enum.Enum):
    STATIC = "static"  # never moves (ODE: a geom without a body)
    KINEMATIC = "kinematic"  # moved by the runner, with velocity, unaffected by forces
    DYNAMIC = "dynamic"  # simulated


class ShapeKind(str, enum.Enum):
    BOX = "box"
    SPHERE = "sphere"
    CAPSULE = "capsule"
    CYLINDER = "cylinder"
    PLANE = "plane"
    COMPOUND = "compound"  # the body's shapes are BodySpec.shapes, at local poses
    CONVEX = "convex"  # Shape.mesh: a convex hull
    TRIMESH = "trimesh"  # Shape.mesh: a triangle mesh, static bodies only


class JointKind(str, enum.Enum):
    SLIDER = "slider"
    HINGE = "hinge"
    BALL = "ball"
    FIXED = "fixed"
    UNIVERSAL = "universal"


class Precision(str, enum.Enum):
    """The floating-point format an engine keeps its state in (positions, velocities, masses, forces).

    Each step rounds every stored number to it, so a state carries rounding that grows with the number
    of steps: docs/semantics.md ("Rounding") bounds it by ``n * eps * scale`` and the expressions' name
    ``eps`` gives an assertion the running engine's :attr:`eps`."""

    FLOAT32 = "float32"
    FLOAT64 = "float64"

    @property
    def eps(self) -> float:
        """Machine epsilon: the gap between 1 and the next number (2^-23 for float32, 2^-52 for float64)."""
        return 2.0**-23 if self is Precision.FLOAT32 else 2.0**-52


class Capability(str, enum.Enum):
    """What a backend can do. The runner checks a world's needs against these before a run starts."""

    SHAPE_BOX = "shape:box"
    SHAPE_SPHERE = "shape:sphere"
    SHAPE_CAPSULE = "shape:capsule"
    SHAPE_CYLINDER = "shape:cylinder"
    SHAPE_PLANE = "shape:plane"
    SHAPE_COMPOUND = "shape:compound"  # several shapes (or none) at local poses in the body frame
    SHAPE_CONVEX = "shape:convex"  # convex hulls of meshes
    SHAPE_TRIMESH = "shape:trimesh"  # triangle meshes on static bodies
    COM_OFFSET = "body:com-offset"  # the centre of mass or principal axes away from the body frame
    COLLISION_FILTER = "collision:exclude-pairs"  # CompiledWorld.excluded_pairs never touch
    JOINT_SLIDER = "joint:slider"
    JOINT_HINGE = "joint:hinge"
    JOINT_BALL = "joint:ball"
    JOINT_FIXED = "joint:fixed"
    JOINT_UNIVERSAL = "joint:universal"
    JOINT_BETWEEN_BODIES = "joint:between-bodies"  # joints whose `other` is a body, not the environment
    JOINT_LIMITS = "joint:limits"
    JOINT_STOP_BOUNCE = "joint:stop-bounce"  # stops with restitution (JointSpec.stop_bounce > 0)
    JOINT_STOP_SOFTNESS = "joint:stop-softness"  # spring-damper stops (JointSpec.stop_stiffness)
    JOINT_MOTOR = "joint:motor"
    CONTACT_BOUNCE = "contact:bounce"  # a contact surface with restitution (Surface.bounce > 0)
    KINEMATIC = "motion:kinematic"
    SUBSTEPS = "world:substeps"
    #: Bodies collide: contact points, normal forces, friction and restitution. Every engine declares it; the
    #: contract suite's contact tests require it. It is not among a world's needs (required_capabilities):
    #: the runner's fake backend, and the minimal engine of tests/outside_engine, run floors without it.
    CONTACTS = "world:contacts"
    # What a model file may hold that only an engine building the robot from the file itself runs
    # (MuJoCo for MJCF, CompiledWorld.models): MODEL_FILE_CAPABILITIES. Several joints per body are every
    # adapter's: the base class builds them as a chain of light bodies (backends/_kit/chains.py).
    JOINT_SEVERAL_PER_BODY = "joint:several-per-body"  # CompiledWorld.joint_chains: one body moved by several joints
    JOINT_ARMATURE = "joint:armature"  # JointDynamics.armature: rotor inertia added to the joint's coordinate
    JOINT_MIMIC = "joint:mimic"  # CompiledWorld.couplings: a joint held at multiplier x its leader + offset
    JOINT_STIFFNESS = "joint:stiffness"  # JointDynamics.stiffness: a spring on the coordinate towards springref
    JOINT_BALL_RANGE = "joint:ball-range"  # a ball joint's cone limit
    JOINT_BALL_DYNAMICS = "joint:ball-dynamics"  # damping, friction loss, armature or stiffness of a ball/free joint
    BODY_MASSLESS = "body:massless"  # a moving body without mass (MuJoCo: its subtree carries the inertia)
    CONSTRAINT_EQUALITY = "constraint:equality"  # MJCF <equality>
    CONSTRAINT_TENDON = "constraint:tendon"  # MJCF <tendon>
    COLLISION_EXPLICIT_PAIRS = "collision:explicit-pairs"  # MJCF <contact><pair>
    #: MJCF <option density viscosity wind>, MuJoCo's inertia-box model (CompiledWorld.fluid): run by MuJoCo from the
    #: file, by the runner's forces before each step on every other engine (runner.sim.fluid)
    WORLD_FLUID = "world:fluid"
    WORLD_FLUID_ELLIPSOID = "world:fluid-ellipsoid"  # MJCF geoms' fluidshape="ellipsoid" (MuJoCo's per-geom model)
    #: an MJCF actuator the scenario drives that the runner's force law cannot reproduce (a site, body or tendon
    #: transmission, activation dynamics): the engine must run the file's actuator itself (Backend.set_control)
    ACTUATOR_NATIVE = "actuator:native"
    # What a run reads beyond states and contact pairs (OUTPUT_CAPABILITIES).
    CONTACT_POINTS = "contacts:points"  # Backend.contact_points(): each touching point, its normal and force
    # Sensing: what a scenario may read that only the engine knows (CompiledWorld.reaction_joints)
    JOINT_REACTION = "joint:reaction"  # Backend.joint_reactions(): the wrench a joint applies to its body


#: Capabilities that no adapter maps to its engine yet (the stop bounce and softness of the language): no
#: backend may declare them until its mapping exists and is tested, so a scenario using them is refused up
#: front with the capability message.
UNMAPPED_CAPABILITIES: frozenset[Capability] = frozenset({Capability.JOINT_STOP_BOUNCE, Capability.JOINT_STOP_SOFTNESS})
#: What robot models (URDF, MJCF) need beyond hand-written bodies (docs/robots.md). Every adapter declares
#: all but ``shape:trimesh``, which ODE and DART declare too; a scenario needing one its backend lacks is
#: refused up front with the capability message.
ROBOT_CAPABILITIES: frozenset[Capability] = frozenset(
    {
        Capability.SHAPE_COMPOUND,
        Capability.SHAPE_CONVEX,
        Capability.SHAPE_TRIMESH,
        Capability.COM_OFFSET,
        Capability.COLLISION_FILTER,
    }
)
#: What only an engine that builds a robot from its model file runs (MuJoCo, for MJCF; docs/robots.md).
MODEL_FILE_CAPABILITIES: frozenset[Capability] = frozenset(
    {
        Capability.JOINT_STIFFNESS,
        Capability.JOINT_BALL_RANGE,
        Capability.JOINT_BALL_DYNAMICS,
        Capability.BODY_MASSLESS,
        Capability.CONSTRAINT_EQUALITY,
        Capability.CONSTRAINT_TENDON,
        Capability.COLLISION_EXPLICIT_PAIRS,
        Capability.WORLD_FLUID_ELLIPSOID,
        Capability.ACTUATOR_NATIVE,
    }
)
#: Every primitive shape; and everything but universal joints and the robot capabilities (what the pybullet,
#: mujoco and dart adapters offer).
ALL_SHAPES: frozenset[Capability] = frozenset(
    c for c in Capability if c.value.startswith("shape:") and c not in ROBOT_CAPABILITIES
)
#: Reads an adapter implements beyond the contract's mandatory ones; each adapter names those it has, so a
#: new adapter (built from ``RIGID_BODY_CAPABILITIES``) refuses them up front until it implements them.
OUTPUT_CAPABILITIES: frozenset[Capability] = frozenset({Capability.CONTACT_POINTS})
#: Sensing capabilities: each adapter adds the ones it implements by name (a new adapter has none until it does).
SENSING_CAPABILITIES: frozenset[Capability] = frozenset({Capability.JOINT_REACTION})
RIGID_BODY_CAPABILITIES: frozenset[Capability] = (
    frozenset(Capability)
    - OUTPUT_CAPABILITIES
    - {Capability.JOINT_UNIVERSAL, Capability.JOINT_ARMATURE, Capability.JOINT_MIMIC}
    - SENSING_CAPABILITIES
    - UNMAPPED_CAPABILITIES
    - ROBOT_CAPABILITIES
    - MODEL_FILE_CAPABILITIES
)


IDENTITY_QUAT: Quat = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Mesh:
    """Triangles in the shape's frame: vertices in metres (scale applied), faces counter-clockwise seen from
    outside (outward normals by the right-hand rule)."""

    vertices: tuple[Vec3, ...]
    faces: tuple[tuple[int, int, int], ...]
    source: str = ""  # the mesh file it came from, for messages and the trace (not a path to open)


@dataclass(frozen=True)
class Shape:
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
class Motor:
    vel: float
    fmax: float


@dataclass(frozen=True)
class JointDynamics:
    """A joint's own dynamics (docs/semantics.md, "Joint dynamics"), in the joint coordinate's units (hinge:
    N m, rad; slider: N, m). Damping and friction loss are realised by the runner with the joint's velocity
    motor (``runner.sim.joint_dynamics``): every engine with ``joint:motor`` runs them. Effort and velocity
    limits cap what the runner commands that motor. Armature and stiffness are the adapter's
    (``joint:armature``, ``joint:stiffness``)."""

    damping: float = 0.0  # N m s/rad or N s/m: a force -damping * rate
    frictionloss: float = 0.0  # N m or N: dry friction, the force that holds the joint still up to this bound
    armature: float = 0.0  # kg m^2 or kg: inertia added to the coordinate (a rotor's reflected inertia)
    stiffness: float = 0.0  # N m/rad or N/m: a spring force -stiffness * (position - springref)
    springref: float = 0.0  # where the spring is relaxed, in the coordinate measured from the start
    effort: float | None = None  # the largest force a motor or servo may apply (caps fmax); None: no cap
    velocity: float | None = None  # the largest rate a motor or servo may command; None: no cap

    @property
    def dissipative(self) -> bool:
        """Whether the runner drives the joint's motor for damping or friction loss."""
        return self.damping > 0 or self.frictionloss > 0


NO_DYNAMICS = JointDynamics()


@dataclass(frozen=True)
class BodySpec:
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
class JointSpec:
    name: str
    kind: JointKind
    body: str
    other: str | None  # None: the environment (the static world)
    axis: Vec3 = (1.0, 0.0, 0.0)  # world frame, unit (slider, hinge; universal: first axis)
    axis2: Vec3 | None = None  # universal: second axis, world frame, unit
    anchor: Vec3 = (0.0, 0.0, 0.0)  # world frame (hinge, ball, universal)
    lo: float | None = None  # stops: metres (slider) or radians (hinge), from the start pose
    hi: float | None = None
    #: restitution of the stops, 0..1 (ODE dParamBounce); 0: no bounce
    stop_bounce: float = 0.0
    #: a soft stop as a spring-damper (N/m or N m/rad; N s/m or N m s/rad), ODE's dParamStopERP/CFM with
    #: ERP = h k / (h k + c) and CFM = 1 / (h k + c) for a step h; None: rigid (the engine's default stop)
    stop_stiffness: float | None = None
    stop_damping: float | None = None
    motor: Motor | None = None  # initial motor; the runner may change it with set_motor
    dynamics: JointDynamics = NO_DYNAMICS


@dataclass(frozen=True)
class JointCoupling:
    """A joint whose position is its leader's, scaled and shifted (URDF `<mimic>`): ``joint`` = ``multiplier`` x
    ``leader`` + ``offset``, both positions counted from the start as every JointSpec's (so ``offset`` is 0
    when the start already satisfies it). Both are sliders or hinges; capability ``joint:mimic``."""

    joint: str  # the follower's CompiledWorld joint name
    leader: str
    multiplier: float
    offset: float = 0.0  # m or rad

    def engine_terms(self, follower_sign: float, leader_sign: float) -> tuple[float, float]:
        """(ratio, offset) of the coupling in an engine's coordinates ``e = sign * q`` of each joint:
        e_joint = ratio * e_leader + offset."""
        return self.multiplier * follower_sign * leader_sign, follower_sign * self.offset


@dataclass(frozen=True)
class PairSurface:
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


@dataclass(frozen=True)
class ImportedBody:
    """A body as the engine holds it once built (:meth:`backends.base.Backend.imported_model`), read back from
    the engine: what it will simulate, whatever the world asked for."""

    name: str  # the CompiledWorld body's name
    mass: float  # kg
    inertia: Vec3  # principal moments about the COM (kg m^2), ascending (the axes are not compared)
    com: Vec3  # the centre of mass in the body frame (m)
    shapes: int  # collision shapes the engine built for the body


@dataclass(frozen=True)
class ImportedJoint:
    """A joint as the engine holds it once built, in the world joint's coordinate (counted from the start, its
    sign), read back from the engine. ``None``: the engine holds no such value (no stop on that side, no own
    damping or friction parameter, no limit it enforces by itself); what the runner realises instead (its
    motor's damping and friction loss, its caps on effort and velocity) is not the engine's and is not here."""

    name: str  # the CompiledWorld joint's name
    kind: JointKind  # the engine's joint type, mapped to ours
    axis: Vec3 | None  # world frame, unit, at the start (slider, hinge; universal: first axis); None: no axis
    lo: float | None  # stops: metres or radians from the start
    hi: float | None
    damping: float | None  # the engine's own joint damping (N m s/rad or N s/m)
    frictionloss: float | None  # the engine's own dry joint friction (N m or N)
    effort: float | None  # a force limit the engine enforces by itself (N m or N)
    velocity: float | None  # a rate limit the engine enforces by itself (rad/s or m/s)


@dataclass(frozen=True)
class ImportedModel:
    """What an engine built, read back before any step: every dynamic body and every joint, in
    ``CompiledWorld`` order (static bodies carry no mass in any engine and are left out)."""

    backend: str
    bodies: tuple[ImportedBody, ...]
    joints: tuple[ImportedJoint, ...]
    #: where a value is the adapter's rather than the engine's (e.g. ODE keeps the COM at the body's origin,
    #: so the COM offset is the adapter's frame), one line each
    notes: tuple[str, ...] = ()


@dataclass
class BodyStates:
    """States of every body in ``CompiledWorld.bodies`` order, world frame."""

    pos: np.ndarray  # (N, 3)
    quat: np.ndarray  # (N, 4), w x y z
    lin_vel: np.ndarray  # (N, 3)
    ang_vel: np.ndarray  # (N, 3)

    @classmethod
    def from_rows(cls, rows: np.ndarray) -> BodyStates:
        """Views of an (N, 13) array whose rows are pos, quat (w x y z), lin_vel, ang_vel."""
        return cls(rows[:, 0:3], rows[:, 3:7], rows[:, 7:10], rows[:, 10:13])

    def rows(self) -> np.ndarray:
        """One (N, 13) float64 array: each row pos, quat (w x y z), lin_vel, ang_vel."""
        return np.hstack((self.pos, self.quat, self.lin_vel, self.ang_vel)).astype(np.float64, copy=False)


@dataclass
class JointStates:
    """States of every joint in ``CompiledWorld.joints`` order (NaN where a value does not exist)."""

    position: np.ndarray  # (M,) slider m / hinge rad; NaN for ball and fixed
    velocity: np.ndarray  # (M,)
    motor_force: np.ndarray  # (M,) force or torque the motor applied in the last step; 0 if none


class Contact(NamedTuple):
    """Touching bodies after the last step (indices into ``CompiledWorld.bodies``, ``a < b``).

    A named tuple rather than a frozen dataclass: adapters make one per touching pair per step, and a
    named tuple is built about 2.5 times faster (0.5 us against 1.2 us).
    """

    a: int
    b: int
    points: int  # number of contact points with distance <= 0
    depth: float  # largest penetration depth, >= 0
    normal_force: float  # summed normal force in N; NaN if the engine cannot say


class ContactPoint(NamedTuple):
    """One contact point of a touching pair (``a < b``, indices into ``CompiledWorld.bodies``) in the last
    engine step of the last scenario step (``Backend.contact_points()``; docs/semantics.md, "Contact points").
    """

    a: int
    b: int
    pos: Vec3  # world frame, m: where the engine places the point (between the two surfaces)
    normal: Vec3  # unit, world frame, pointing from body a to body b: a pushes b along +normal
    depth: float  # penetration, m (>= 0 when touching)
    force: float  # normal force, N, >= 0: the impulse along the normal in that engine step / its length


#: ``Contact`` from a (a, b, points, depth, normal_force) tuple without ``NamedTuple.__new__``'s Python
#: frame (``Contact._make`` minus its length check): for adapters that build one per pair per step.
#: The fields must already be plain ``int`` and ``float``.
new_contact: Callable[[tuple[int, int, int, float, float]], Contact] = partial(tuple.__new__, Contact)
