"""What a backend can do (:class:`Capability`) and the named sets of capabilities adapters build theirs from;
the runner checks a world's needs against them before a run starts (re-exported by :mod:`backends.types`)."""

from __future__ import annotations

import enum


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
