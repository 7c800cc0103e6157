"""Build a DART world from a CompiledWorld (docs/backends/dart.md, "Mapping").

One Skeleton per tree of ``_trees.plan``: a free body has a FreeJoint root, a static body a WeldJoint
root, a kinematic body a FreeJoint driven by a VELOCITY actuator; joints become Prismatic / Revolute /
Ball / Weld joints whose frames sit at the anchor with world-aligned axes at the start, so that every
slider and hinge coordinate starts at 0 and its axis is the world axis. Shapes use full sizes and DART's
z-aligned capsules and cylinders (``height`` = the cylindrical part for a capsule, as ODE's ``length``).
With ``friction: cone`` the constraint solver's LCP solver is DART's ``NsgsFrictionSolver`` with its
exact Coulomb law (a friction cone per contact, DART's default PGS as the fallback when it does not
converge); DART's own Dantzig solver bounds each of two tangent rows by mu*N, a pyramid whose edges
follow the contact normal's basis (world x and y on a floor).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from importlib.metadata import version
from typing import Any

import dartpy as dart
import numpy as np

from ..errors import BackendNotInstalled, UnsupportedFeature
from ..types import IDENTITY_QUAT, BodySpec, CompiledWorld, JointKind, JointSpec, Motion, Shape, ShapeKind
from . import _contact_params, _meshes, _surfaces, _trees
from ._options import CONE_MAX_SWEEPS

#: The detector of each ``collision_detector`` option value (``_options.DETECTOR_NAMES``, in that order).
DETECTORS: dict[str, Any] = {
    "ode": dart.collision.OdeCollisionDetector,
    "fcl": dart.collision.FCLCollisionDetector,
    "bullet": dart.collision.BulletCollisionDetector,
    "dart": dart.collision.DARTCollisionDetector,
}
_PAIR_FACTORY = {
    JointKind.SLIDER: "createPrismaticJointAndBodyNodePair",
    JointKind.HINGE: "createRevoluteJointAndBodyNodePair",
    JointKind.BALL: "createBallJointAndBodyNodePair",
    JointKind.FIXED: "createWeldJointAndBodyNodePair",
}


@dataclass
class BodyHandle:
    spec: BodySpec
    skeleton: Any
    node: Any
    free: bool  # the skeleton is this one body on a FreeJoint: states come from two batched reads
    aspects: tuple[Any, ...] = ()  # its shapes' DynamicsAspects (friction, restitution); none for no shape
    root: Any = None  # the skeleton's root joint (a FreeJoint for free and kinematic roots)
    com: Any = None  # the centre of mass in the body frame where it is not the origin (forces act there)


@dataclass
class JointHandle:
    spec: JointSpec
    joint: Any
    sign: float  # see _trees: -1 when the tree runs opposite to the world joint
    vel: float = 0.0  # motor, in the world joint's coordinate
    fmax: float = 0.0


@dataclass
class Built:
    world: Any
    bodies: list[BodyHandle]
    joints: list[JointHandle]
    coefficients: _surfaces.ShapeCoefficients
    skeletons: list[Any] = field(default_factory=list)


def isometry(pos: Any, quat: Any) -> Any:
    """A DART Isometry3 from a position and a (w, x, y, z) quaternion."""
    t = dart.math.Isometry3()
    t.set_identity()
    t.set_quaternion(dart.math.Quaternion(float(quat[0]), float(quat[1]), float(quat[2]), float(quat[3])))
    t.set_translation(np.asarray(pos, dtype=float))
    return t


def _translation(pos: Any) -> Any:
    return isometry(pos, (1.0, 0.0, 0.0, 0.0))


def make_shape(shape: Shape) -> Any:
    """A DART shape in its body's frame (a plane: normal +z through the body's origin)."""
    if shape.kind is ShapeKind.BOX:
        return dart.dynamics.BoxShape(np.asarray(shape.size, dtype=float))
    if shape.kind is ShapeKind.SPHERE:
        return dart.dynamics.SphereShape(shape.radius)
    if shape.kind is ShapeKind.CAPSULE:
        return dart.dynamics.CapsuleShape(shape.radius, shape.length)
    if shape.kind is ShapeKind.CYLINDER:
        return dart.dynamics.CylinderShape(shape.radius, shape.length)
    if shape.kind in (ShapeKind.CONVEX, ShapeKind.TRIMESH) and shape.mesh is not None:
        return _meshes.mesh_shape(shape.mesh)
    return dart.dynamics.PlaneShape(np.array([0.0, 0.0, 1.0]), 0.0)


@functools.cache
def check_conventions() -> None:
    """Refuse a dartpy whose FreeJoint coordinates differ from those this adapter reads (6.20's).

    The batched reads rely on FreeJoint positions being [rotation vector, translation] and velocities
    [angular, linear] in the world frame; older DART releases used body-frame velocities.
    """
    skeleton = dart.dynamics.Skeleton("probe")
    joint, node = skeleton.createFreeJointAndBodyNodePair()
    quarter = (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))  # 90 degrees about z
    place_free(joint, (1.0, 2.0, 3.0), quarter, (1.0, 0.0, 0.0), (0.0, 0.0, 0.5))
    expected = np.array([0.0, 0.0, math.pi / 2, 1.0, 2.0, 3.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0])
    got = np.concatenate([skeleton.getPositions(), skeleton.getVelocities()])
    world_vel = np.concatenate([node.getAngularVelocity(), node.getLinearVelocity()])
    if not (np.allclose(got, expected, atol=1e-12) and np.allclose(world_vel, expected[6:], atol=1e-12)):
        raise BackendNotInstalled(
            f"Backend `dart` reads FreeJoint coordinates as dartpy 6.20 defines them; the installed "
            f"dartpy {version('dartpy')} differs. Install it with: pip install 'dartpy==6.20.*'"
        )


def build(
    world: CompiledWorld, detector: str, coefficients: _surfaces.ShapeCoefficients, engine_steps: int,
    friction: str = "pyramid",
) -> Built:
    check_conventions()
    _contact_params.apply()
    dw = dart.simulation.World(world.name)
    dw.setGravity(np.asarray(world.gravity, dtype=float))
    dw.setTimeStep(world.dt / engine_steps)
    sleep = dw.getDeactivationOptions()
    sleep.mEnabled = False  # DART puts slow bodies to sleep by default; ODE's auto-disable is off
    dw.setDeactivationOptions(sleep)
    solver = dw.getConstraintSolver()
    solver.setCollisionDetector(DETECTORS[detector]())
    if friction == "cone":
        options = dart.constraint.NsgsFrictionSolver.Options()
        options.law = dart.constraint.NsgsFrictionSolver.Law.Coulomb
        options.maxSweeps = CONE_MAX_SWEEPS
        solver.setBoxedLcpSolver(dart.constraint.NsgsFrictionSolver(options))
    built = Built(dw, [None] * len(world.bodies), [None] * len(world.joints), coefficients)  # type: ignore[list-item]
    for tree in _trees.plan(world):
        built.skeletons.append(_build_tree(world, tree, built))
    for skeleton in built.skeletons:
        dw.addSkeleton(skeleton)
    _exclude_pairs(world, built, solver)
    return built


def check(world: CompiledWorld) -> None:
    """Refuse what :func:`build` would refuse in the world's joint trees, in its order, from the world alone
    (no engine call): a closed loop, a joint kind DART has no pair for, a jointed child that is not dynamic, a
    plane that moves or hangs from a joint."""
    bodies = world.bodies
    for tree in _trees.plan(world):
        if tree.root_joint is not None:
            _check_kind(world.joints[tree.root_joint])
        _check_plane(bodies[tree.root], jointed=False)
        for link in tree.links:
            spec, child = world.joints[link.joint], bodies[link.child]
            if child.motion is not Motion.DYNAMIC:
                raise UnsupportedFeature(f"Backend `dart` needs `{child.name}` of joint `{spec.name}` to be dynamic.")
            _check_kind(spec)
            _check_plane(child, jointed=True)


def _check_kind(spec: JointSpec) -> None:
    if spec.kind not in _PAIR_FACTORY:
        raise UnsupportedFeature(f"Backend `dart` does not support {spec.kind.value} joints (`{spec.name}`).")


def _check_plane(spec: BodySpec, jointed: bool) -> None:
    if spec.shape.kind is ShapeKind.PLANE and (spec.motion is not Motion.STATIC or jointed):
        raise UnsupportedFeature(f"Plane `{spec.name}` must be static and unjointed (planes never move).")


def _exclude_pairs(world: CompiledWorld, built: Built, solver: Any) -> None:
    """Black-list ``excluded_pairs`` in the constraint solver's own BodyNodeCollisionFilter (DART's default
    filter, which also applies each skeleton's self-collision and adjacent-body settings): those pairs get
    no contact, so no force and no entry in the collision result that ``contacts()`` reads."""
    if not world.excluded_pairs:
        return
    found = solver.getCollisionOption().collisionFilter
    if not isinstance(found, dart.collision.BodyNodeCollisionFilter):
        raise UnsupportedFeature(f"Backend `dart` found no BodyNodeCollisionFilter to exclude pairs with ({found}).")
    nodes = {handle.spec.name: handle.node for handle in built.bodies}
    for a, b in world.excluded_pairs:
        found.addBodyNodePairToBlackList(nodes[a], nodes[b])


def _build_tree(world: CompiledWorld, tree: _trees.Tree, built: Built) -> Any:
    bodies = world.bodies
    root = bodies[tree.root]
    skeleton = dart.dynamics.Skeleton(f"{tree.root}:{root.name}")
    if tree.root_joint is not None:
        spec = world.joints[tree.root_joint]
        joint, node = _joint_pair(skeleton, None, spec, None, root, 1.0)
        built.joints[tree.root_joint] = JointHandle(spec, joint, 1.0)
        _initial_rate(joint, spec, root, None)
    elif root.motion is Motion.STATIC:
        joint, node = skeleton.createWeldJointAndBodyNodePair()
        joint.setTransformFromParentBodyNode(isometry(root.pos, root.quat))
    else:
        joint, node = skeleton.createFreeJointAndBodyNodePair()
        if root.motion is Motion.KINEMATIC:
            joint.setActuatorType(dart.dynamics.ActuatorType.VELOCITY)
    nodes = {tree.root: node}
    aspects = {tree.root: _dress(node, tree.root, root, built)}
    for link in tree.links:
        spec, child = world.joints[link.joint], bodies[link.child]
        if child.motion is not Motion.DYNAMIC:
            raise UnsupportedFeature(f"Backend `dart` needs `{child.name}` of joint `{spec.name}` to be dynamic.")
        joint, node = _joint_pair(skeleton, nodes[link.parent], spec, bodies[link.parent], child, link.sign)
        built.joints[link.joint] = JointHandle(spec, joint, link.sign)
        _initial_rate(joint, spec, child, bodies[link.parent])
        nodes[link.child] = node
        aspects[link.child] = _dress(node, link.child, child, built)
    if tree.links:
        # Jointed bodies of one tree collide with each other, except a parent with its child (as the
        # other engines filter jointed pairs).
        skeleton.enableSelfCollisionCheck()
        skeleton.disableAdjacentBodyCheck()
    free = tree.root_joint is None and root.motion is not Motion.STATIC and not tree.links
    root_joint = skeleton.getRootJoint()
    for i in tree.bodies:
        com = None if bodies[i].com == (0.0, 0.0, 0.0) else np.asarray(bodies[i].com, dtype=float)
        built.bodies[i] = BodyHandle(bodies[i], skeleton, nodes[i], free, aspects[i], root_joint, com)
    if tree.root_joint is None and root.motion is not Motion.STATIC:
        place_free(root_joint, root.pos, root.quat, root.lin_vel, root.ang_vel)
    return skeleton


def _joint_pair(
    skeleton: Any, parent_node: Any, spec: JointSpec, parent: BodySpec | None, child: BodySpec, sign: float
) -> tuple[Any, Any]:
    """A joint whose frame is at the anchor (slider, fixed: the child's centre), world-aligned at start."""
    if spec.kind not in _PAIR_FACTORY:
        raise UnsupportedFeature(f"Backend `dart` does not support {spec.kind.value} joints (`{spec.name}`).")
    factory = getattr(skeleton, _PAIR_FACTORY[spec.kind])
    joint, node = factory() if parent_node is None else factory(parent_node)
    at = spec.anchor if spec.kind in (JointKind.HINGE, JointKind.BALL) else child.pos
    frame = _translation(at)
    from_parent = frame if parent is None else isometry(parent.pos, parent.quat).inverse().multiply(frame)
    joint.setTransformFromParentBodyNode(from_parent)
    joint.setTransformFromChildBodyNode(isometry(child.pos, child.quat).inverse().multiply(frame))
    if spec.kind in (JointKind.SLIDER, JointKind.HINGE):
        joint.setAxis(np.asarray(spec.axis, dtype=float))
        lo = -math.inf if spec.lo is None else spec.lo
        hi = math.inf if spec.hi is None else spec.hi
        lo, hi = (lo, hi) if sign > 0 else (-hi, -lo)
        joint.setPositionLowerLimit(0, lo)
        joint.setPositionUpperLimit(0, hi)
        joint.setLimitEnforcement(spec.lo is not None or spec.hi is not None)
        joint.setActuatorType(dart.dynamics.ActuatorType.PASSIVE)
        joint.setDampingCoefficient(0, spec.dynamics.damping)  # DART's own, implicit (DartBackend.native_damping)
        joint.setSpringStiffness(0, spec.dynamics.stiffness)  # DART's own spring, implicit like its damping
        joint.setRestPosition(0, sign * spec.dynamics.springref)  # in DART's coordinate (sign: _trees)
    return joint, node


def _dress(node: Any, index: int, spec: BodySpec, built: Built) -> tuple[Any, ...]:
    """Name, shapes (named by the body's index), friction, restitution and mass of one body.

    A primitive body's one shape node is named ``"<index>"``; a compound body's are ``"<index>:<k>"`` at
    their local poses (the contact reader takes the body from the part before the colon).
    """
    node.setName(spec.name)
    if spec.shape.kind is ShapeKind.PLANE and (spec.motion is not Motion.STATIC or node.getParentBodyNode()):
        raise UnsupportedFeature(f"Plane `{spec.name}` must be static and unjointed (planes never move).")
    compound = spec.shape.kind is ShapeKind.COMPOUND
    aspects = []
    for k, placed in enumerate(spec.placed_shapes()):
        shape = make_shape(placed.shape)
        shape_node = node.createShapeNode(shape, f"{index}:{k}" if compound else f"{index}")
        if compound:
            shape_node.setRelativeTransform(isometry(placed.pos, placed.quat))
        shape_node.createCollisionAspect()
        aspect = shape_node.createDynamicsAspect()
        aspect.setFrictionCoeff(built.coefficients.friction[index])
        aspect.setRestitutionCoeff(built.coefficients.restitution[index])
        aspects.append(aspect)
    if spec.mass > 0.0:
        node.setInertia(_inertia(spec))
    return tuple(aspects)


def _inertia(spec: BodySpec) -> Any:
    """The body's mass properties, from its fields only (never from its shapes): DART's ``Inertia`` takes
    the COM in the body frame and the tensor about it in the body frame, which ``inertia_tensor()`` is."""
    if spec.com != (0.0, 0.0, 0.0) or spec.inertia_quat != IDENTITY_QUAT or spec.shape.kind is ShapeKind.COMPOUND:
        return dart.dynamics.Inertia(spec.mass, np.asarray(spec.com, dtype=float), spec.inertia_tensor())
    moments = make_shape(spec.shape).computeInertia(spec.mass)
    if not np.allclose(np.diag(moments), spec.inertia, rtol=1e-9, atol=0.0):
        moments = np.diag(np.asarray(spec.inertia, float))  # the world's inertia is the contract
    return dart.dynamics.Inertia(spec.mass, np.zeros(3), moments)


def place_free(joint: Any, pos: Any, quat: Any, lin_vel: Any, ang_vel: Any) -> None:
    """Pose and world-frame velocities of a FreeJoint ([rotation vector, translation], [w, v]).

    Set on the joint, not the skeleton: a skeleton with jointed children has more coordinates, and
    ``Skeleton.setPositions`` with too few entries only prints an error and sets nothing.
    """
    joint.setPositions(dart.dynamics.FreeJoint.convertToPositions(isometry(pos, quat)))
    joint.setVelocities(np.concatenate([np.asarray(ang_vel, float), np.asarray(lin_vel, float)]))


def _initial_rate(joint: Any, spec: JointSpec, child: BodySpec, parent: BodySpec | None) -> None:
    """A slider's or hinge's starting rate: the child's initial velocity relative to the parent's, on the axis."""
    if spec.kind is JointKind.SLIDER:
        rel = np.subtract(child.lin_vel, parent.lin_vel if parent else (0.0, 0.0, 0.0))
    elif spec.kind is JointKind.HINGE:
        rel = np.subtract(child.ang_vel, parent.ang_vel if parent else (0.0, 0.0, 0.0))
    else:
        return
    joint.setVelocity(0, float(np.dot(rel, spec.axis)))  # tree child relative to tree parent
