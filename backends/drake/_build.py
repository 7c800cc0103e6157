"""A CompiledWorld as a Drake MultibodyPlant + SceneGraph diagram (docs/backends/drake.md, "Mapping").

* Static bodies are geometry on the world body (a plane is a ``HalfSpace``). Dynamic bodies are rigid
  bodies with the world's mass, COM and inertia (``SpatialInertia.MakeFromCentralInertia``); Drake gives
  a body without a joint a floating joint at ``Finalize``.
* Kinematic bodies (Drake has none: RobotLocomotion/drake#20496) are free bodies
  :data:`KINEMATIC_MASS_RATIO` times heavier than the heaviest dynamic body, their weight cancelled by a
  force, their pose and velocity imposed before every engine step (the adapter), as the MuJoCo adapter does.
* Joints are Drake joints between frames at the anchor with the world's orientation at the start, so the
  start is q = 0: slider -> ``PrismaticJoint``, hinge -> ``RevoluteJoint``, ball -> ``BallRpyJoint``, fixed
  -> ``WeldJoint``; stops are the joint's position limits (SAP limit constraints). Every slider and hinge
  gets a PD actuator (Kp 0, Kd ``motor_gain``) whose effort limit is ``fmax``: Drake clamps the PD force
  inside the discrete solve, ODE's velocity motor. A joint's armature is that actuator's rotor inertia, its
  stiffness a ``RevoluteSpring`` / ``PrismaticSpring`` (``_joint_dynamics``).
* Convex hulls: ``Convex`` from the hull's vertices (an in-memory OBJ; Drake takes their hull), compliant
  hydroelastic like every moving shape (Drake tessellates a convex hull itself: tetrahedra from its faces to
  its centroid, pressure 0 on the surface and E at the centroid; the resolution hint is not used).
* Friction: one ``CoulombFriction`` per geometry from ``_friction.solve`` (static = dynamic = mu).
* Collision filters: Drake's own filter of joined bodies is off; the adapter excludes the pairs of
  ``touching_pairs``' complement (joined bodies, excluded pairs, static or kinematic with each other).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydrake.common import MemoryFile
from pydrake.common.eigen_geometry import Quaternion
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    AddRigidHydroelasticProperties,
    Box,
    Capsule,
    CollisionFilterDeclaration,
    Convex,
    Cylinder,
    GeometrySet,
    HalfSpace,
    InMemoryMesh,
    ProximityProperties,
    Sphere,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlantConfig
from pydrake.multibody.tree import (
    BallRpyJoint,
    FixedOffsetFrame,
    PdControllerGains,
    PrismaticJoint,
    RevoluteJoint,
    RotationalInertia,
    SpatialInertia,
    WeldJoint,
)
from pydrake.systems.framework import DiagramBuilder

from ..errors import UnsupportedFeature
from ..types import BodySpec, CompiledWorld, JointKind, JointSpec, Motion, Shape, ShapeKind
from . import _friction, _joint_dynamics
from ._options import DrakeOptions

#: A kinematic body's mass over the heaviest dynamic body's (at least 1 kg): what rests on it or hits it
#: changes its velocity by at most 1e-6 of what it would do to an equal body, and the adapter re-imposes
#: the pose and velocity before every engine step anyway.
KINEMATIC_MASS_RATIO = 1e6
#: The resolution hint of compliant hydroelastic meshes, as a fraction of a shape's smallest dimension.
HYDRO_RESOLUTION = 0.1


@dataclass
class JointHandle:
    spec: JointSpec
    joint: Any  # the Drake joint
    sign: float  # the world's coordinate = sign * Drake's (-1 when the tree runs from body to other)
    actuator: Any = None  # the PD actuator of a slider or hinge


@dataclass
class Built:
    diagram: Any
    plant: Any
    scene_graph: Any
    bodies: list[Any]  # per world body: the Drake RigidBody (None for static bodies)
    joints: list[JointHandle]
    geometry_body: dict[int, int]  # GeometryId value -> world body index
    friction: tuple[float, ...]
    actuated: list[int] = field(default_factory=list)  # world joint per actuator, in JointActuatorIndex order


def tree(world: CompiledWorld) -> list[tuple[str | None, str, float]]:
    """(parent, child, sign) per joint: Drake's joints form a tree, each body the child of one joint at most.

    The joints are oriented away from the world (static bodies and the environment are the world) or, in a
    group of bodies not joined to it, from the group's first body; a joint whose ``body`` ends up the parent
    reads its coordinate negated (sign -1). Raises UnsupportedFeature for a loop of joints and for joints on
    kinematic bodies (no engine call)."""
    motion = {b.name: b.motion for b in world.bodies}
    ends: list[tuple[str | None, str]] = []
    root: dict[str | None, str | None] = {None: None}

    def find(node: str | None) -> str | None:
        while root.setdefault(node, node) != node:
            node = root[node]
        return node

    for joint in world.joints:
        for name in (joint.body, joint.other):
            if name is not None and motion[name] is Motion.KINEMATIC:
                raise UnsupportedFeature(
                    f"Backend `drake` drives a kinematic body as a heavy free body, which no joint may hold; joint "
                    f"`{joint.name}` holds kinematic body `{name}`."
                )
        if motion[joint.body] is Motion.STATIC:
            raise UnsupportedFeature(f"Backend `drake`: joint `{joint.name}` moves static body `{joint.body}`.")
        other = None if joint.other is None or motion[joint.other] is Motion.STATIC else joint.other
        a, b = find(joint.body), find(other)
        if a == b:
            raise UnsupportedFeature(
                f"Backend `drake` builds joints as a tree (Drake's MultibodyPlant); joint `{joint.name}` closes a "
                f"loop of joints between `{joint.body}` and `{joint.other or 'the environment'}`."
            )
        if b is None:  # keep the world as the root of its group
            a, b = b, a
        root[b] = a
        ends.append((other, joint.body))
    adjacent: dict[str | None, list[int]] = {}
    for k, (other, body) in enumerate(ends):
        adjacent.setdefault(other, []).append(k)
        adjacent.setdefault(body, []).append(k)
    oriented: dict[int, tuple[str | None, str, float]] = {}
    starts = [None, *(b.name for b in world.bodies if b.name in adjacent)]
    placed: set[str | None] = set()
    for start in starts:
        if start in placed or start not in adjacent:
            continue
        placed.add(start)
        queue = [start]
        for node in queue:  # breadth first; `queue` grows while iterating
            for k in adjacent[node]:
                if k in oriented:
                    continue
                other, body = ends[k]
                child = body if node == other else (other or body)  # the world (None) is only ever a root
                oriented[k] = (node, child, 1.0 if child == body else -1.0)
                placed.add(child)
                queue.append(child)
    return [oriented[k] for k in range(len(ends))]


def check(world: CompiledWorld) -> None:
    """What the build would refuse, judged without the engine."""
    tree(world)
    _friction.solve(world)
    _joint_dynamics.check(world)
    for body in world.bodies:
        if body.motion is not Motion.STATIC and body.mass <= 0.0:
            raise UnsupportedFeature(f"Backend `drake` needs a positive mass on moving body `{body.name}`.")
        for placed in body.placed_shapes():
            if placed.shape.kind is ShapeKind.PLANE and body.motion is not Motion.STATIC:
                raise UnsupportedFeature(f"Backend `drake`: plane `{body.name}` must be static.")


def check_hulls(world: CompiledWorld, options: Any) -> None:
    """Refuse convex hulls under point contact: Drake's point query gives one point per hull pair (a hull box
    on a plane touches at one corner, tips onto it and rests 45.6 mm deep; a ``Box`` gets its face's centre)."""
    if getattr(options, "contact_model", "") != "point":
        return
    for body in world.bodies:
        for placed in body.placed_shapes():
            if placed.shape.kind is ShapeKind.CONVEX:
                raise UnsupportedFeature(
                    f"Backend `drake` with `contact_model: point` does not run shape:convex (body `{body.name}`): "
                    "Drake's point contact touches a hull at one vertex (a hull box on a plane rests 45.6 mm deep); "
                    "use the default contact_model hydroelastic_with_fallback"
                )


def vec(values: Any) -> Any:
    """A float64 array typed Any (pydrake's stubs accept no numpy annotation)."""
    return np.asarray(values, dtype=float)


def _transform(pos: Any, quat: Any) -> RigidTransform:
    w, x, y, z = (float(v) for v in quat)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    return RigidTransform(Quaternion(w / n, x / n, y / n, z / n), vec(pos))


def _obj(shape: Shape) -> str:
    if shape.mesh is None:
        raise UnsupportedFeature(f"Backend `drake`: convex shape without a mesh ({shape})")
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in shape.mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in shape.mesh.faces]
    return "\n".join(lines) + "\n"


def _geometry(shape: Shape, label: str) -> Any:
    kind = shape.kind
    if kind is ShapeKind.BOX:
        return Box(*shape.size)
    if kind is ShapeKind.SPHERE:
        return Sphere(shape.radius)
    if kind is ShapeKind.CAPSULE:
        return Capsule(shape.radius, shape.length)
    if kind is ShapeKind.CYLINDER:
        return Cylinder(shape.radius, shape.length)
    if kind is ShapeKind.PLANE:
        return HalfSpace()
    if kind is ShapeKind.CONVEX:
        return Convex(InMemoryMesh(mesh_file=MemoryFile(_obj(shape), ".obj", label)))
    raise UnsupportedFeature(f"Backend `drake` has no mapping for shape kind `{kind.value}` ({label}).")


def _smallest(shape: Shape) -> float:
    if shape.kind is ShapeKind.BOX:
        return float(min(shape.size))
    if shape.kind is ShapeKind.CONVEX and shape.mesh is not None:
        v = np.asarray(shape.mesh.vertices)
        return float((v.max(axis=0) - v.min(axis=0)).min())
    return 2.0 * shape.radius


def _properties(shape: Shape, mu: float, options: DrakeOptions, static: bool) -> ProximityProperties:
    """Friction, and for hydroelastic contact: static geometry rigid, moving geometry compliant (Drake has no
    compliant-compliant half space contact; a rigid-rigid pair falls back to point contact)."""
    props = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(mu, mu), properties=props)
    if options.contact_model != "point":
        modulus = options.hydroelastic_modulus
        if shape.kind is ShapeKind.PLANE:
            AddRigidHydroelasticProperties(props)
        elif static:
            AddRigidHydroelasticProperties(HYDRO_RESOLUTION * _smallest(shape), props)
        else:
            AddCompliantHydroelasticProperties(HYDRO_RESOLUTION * _smallest(shape), modulus, props)
    return props


def _inertia(body: BodySpec, mass: float, inertia: Any) -> SpatialInertia:
    tensor = body.inertia_tensor() * (mass / body.mass if body.mass > 0 else 1.0) if inertia is None else inertia
    central = RotationalInertia(tensor[0, 0], tensor[1, 1], tensor[2, 2], tensor[0, 1], tensor[0, 2], tensor[1, 2])
    return SpatialInertia.MakeFromCentralInertia(mass, vec(body.com), central)


def build(world: CompiledWorld, options: DrakeOptions, h: float) -> Built:
    """The diagram of ``world`` with engine steps of ``h`` seconds (finalized, not yet given a context)."""
    builder = DiagramBuilder()
    config = MultibodyPlantConfig(
        time_step=h,
        contact_model=options.contact_model,
        discrete_contact_approximation=options.approximation,
        penetration_allowance=options.penetration_allowance,
        adjacent_bodies_collision_filters=False,
    )
    plant, scene_graph = AddMultibodyPlant(config, builder)
    plant.mutable_gravity_field().set_gravity_vector(vec(world.gravity))
    friction = _friction.solve(world)
    heavy = KINEMATIC_MASS_RATIO * max([1.0] + [b.mass for b in world.bodies if b.motion is Motion.DYNAMIC])
    bodies: list[Any] = []
    geometry_body: dict[int, int] = {}
    geometries: list[list[Any]] = []
    for i, spec in enumerate(world.bodies):
        if spec.motion is Motion.STATIC:
            frame_body, x_wb = plant.world_body(), _transform(spec.pos, spec.quat)
            bodies.append(None)
        else:
            mass = heavy if spec.motion is Motion.KINEMATIC else spec.mass
            inertia = None
            if spec.motion is Motion.KINEMATIC:  # as heavy as a solid sphere of 1 m radius of that mass, at least
                inertia = np.eye(3) * heavy * 0.4 + spec.inertia_tensor() * (heavy / max(spec.mass, 1e-12))
            frame_body, x_wb = plant.AddRigidBody(spec.name, _inertia(spec, mass, inertia)), RigidTransform()
            bodies.append(frame_body)
        ids = []
        for k, placed in enumerate(spec.placed_shapes()):
            label = f"{spec.name}#{k}"
            x_bg = x_wb.multiply(_transform(placed.pos, placed.quat))
            gid = plant.RegisterCollisionGeometry(
                frame_body,
                x_bg,
                _geometry(placed.shape, label),
                label,
                _properties(placed.shape, friction[i], options, spec.motion is Motion.STATIC),
            )
            geometry_body[gid.get_value()] = i
            ids.append(gid)
        geometries.append(ids)
    joints = _joints(world, plant, bodies, options)
    _couple(world, plant, joints)
    plant.Finalize()
    _filters(world, scene_graph, geometries)
    actuated = [j for j, h in sorted(((j, h) for j, h in enumerate(joints) if h.actuator is not None),
                                     key=lambda item: int(item[1].actuator.index()))]  # fmt: skip
    diagram = builder.Build()
    return Built(diagram, plant, scene_graph, bodies, joints, geometry_body, friction, actuated)


def _couple(world: CompiledWorld, plant: Any, joints: list[JointHandle]) -> None:
    """Each coupling (URDF `<mimic>`, ``joint:mimic``) as Drake's own coupler constraint (what its URDF parser
    makes of `<mimic>`): q0 = gear_ratio q1 + offset in Drake's coordinates (``sign`` x the world's), solved
    by SAP with the contacts and limits."""
    index = {spec.name: k for k, spec in enumerate(world.joints)}
    for coupling in world.couplings:
        follower, leader = joints[index[coupling.joint]], joints[index[coupling.leader]]
        ratio, offset = coupling.engine_terms(follower.sign, leader.sign)
        plant.AddCouplerConstraint(joint0=follower.joint, joint1=leader.joint, gear_ratio=ratio, offset=offset)


def _joint_frames(plant: Any, spec: JointSpec, parent: str | None, child: str,
                  specs: dict[str, BodySpec]) -> tuple[Any, Any]:  # fmt: skip
    """Frames at the anchor with the world's orientation at the start, on the parent and on the child."""
    x_wj = RigidTransform(vec(spec.anchor))
    frames = []
    for name in (parent, child):
        if name is None:
            x_bj, base = x_wj, plant.world_frame()
        else:
            b = specs[name]
            x_bj = _transform(b.pos, b.quat).InvertAndCompose(x_wj)
            base = plant.GetBodyByName(name).body_frame()
        frames.append(plant.AddFrame(FixedOffsetFrame(f"{spec.name}:{name or 'world'}", base, x_bj)))
    return frames[0], frames[1]


def _joints(world: CompiledWorld, plant: Any, bodies: list[Any], options: DrakeOptions) -> list[JointHandle]:
    specs = {b.name: b for b in world.bodies}
    handles = []
    for spec, (parent, child, sign) in zip(world.joints, tree(world), strict=True):
        f_parent, f_child = _joint_frames(plant, spec, parent, child, specs)
        axis = vec(spec.axis)
        lo = -math.inf if spec.lo is None else spec.lo
        hi = math.inf if spec.hi is None else spec.hi
        if sign < 0:
            lo, hi = -hi, -lo
        if spec.kind is JointKind.SLIDER:
            joint = plant.AddJoint(PrismaticJoint(spec.name, f_parent, f_child, axis, lo, hi))
        elif spec.kind is JointKind.HINGE:
            joint = plant.AddJoint(RevoluteJoint(spec.name, f_parent, f_child, axis, lo, hi))
        elif spec.kind is JointKind.BALL:
            joint = plant.AddJoint(BallRpyJoint(spec.name, f_parent, f_child))
        elif spec.kind is JointKind.FIXED:
            joint = plant.AddJoint(WeldJoint(spec.name, f_parent, f_child, RigidTransform()))
        else:
            raise UnsupportedFeature(f"Backend `drake` does not map `{spec.kind.value}` joints (joint `{spec.name}`).")
        handle = JointHandle(spec, joint, sign)
        if spec.kind in (JointKind.SLIDER, JointKind.HINGE):
            fmax = spec.motor.fmax if spec.motor is not None else 0.0
            handle.actuator = plant.AddJointActuator(f"motor:{spec.name}", joint, effort_limit=max(fmax, 1e-30))
            handle.actuator.set_controller_gains(PdControllerGains(p=0.0, d=options.motor_gain))
            _joint_dynamics.add(plant, handle)  # armature (the actuator's rotor inertia) and spring
        handles.append(handle)
    return handles


def _filters(world: CompiledWorld, scene_graph: Any, geometries: list[list[Any]]) -> None:
    """Exclude every geometry pair of bodies that cannot touch (``_friction.touching_pairs``' complement)."""
    touching = set(_friction.touching_pairs(world))
    manager = scene_graph.collision_filter_manager()
    n = len(world.bodies)
    for a in range(n):
        for b in range(a + 1, n):
            if (a, b) in touching or not geometries[a] or not geometries[b]:
                continue
            if world.bodies[a].motion is Motion.STATIC and world.bodies[b].motion is Motion.STATIC:
                continue  # on the world body both: never collide
            manager.Apply(CollisionFilterDeclaration().ExcludeBetween(GeometrySet(geometries[a]),
                                                                      GeometrySet(geometries[b])))  # fmt: skip
    for a in range(n):
        if len(geometries[a]) > 1 and world.bodies[a].motion is not Motion.STATIC:
            manager.Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(geometries[a])))


__all__ = ["KINEMATIC_MASS_RATIO", "Built", "JointHandle", "build", "check", "check_hulls", "tree", "vec"]
