"""Build a panda3d.ode world from a CompiledWorld, as the lab's PyODE program does.

Dynamic bodies get an ``OdeBody`` whose ``OdeMass`` is set with ``setParameters`` to the world's mass and
principal inertia (already ODE's dMassSet* values); static bodies are bodiless geoms; kinematic bodies
are bodies with gravity off and a huge mass (KINEMATIC_MASS_RATIO), re-placed by the backend after every
step. Collision filtering uses ODE's category/collide bits, so static-static, static-kinematic and
kinematic-kinematic pairs are never tested (ODE collides a pair when either geom's category matches the
other's collide bits). A cylinder that a capsule can touch also gets a prism stand-in, tested against
capsules only (``_colliders``: panda3d's ODE has no capsule-cylinder collider).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from panda3d.core import BitMask32, Quat
from panda3d.ode import (
    OdeBallJoint,
    OdeBody,
    OdeBoxGeom,
    OdeCappedCylinderGeom,
    OdeCylinderGeom,
    OdeFixedJoint,
    OdeHashSpace,
    OdeHingeJoint,
    OdeJointFeedback,
    OdeJointGroup,
    OdeMass,
    OdePlaneGeom,
    OdeSimpleSpace,
    OdeSliderJoint,
    OdeSphereGeom,
    OdeTriMeshGeom,
    OdeUniversalJoint,
    OdeWorld,
)

from ..errors import UnsupportedFeature
from ..geometry import quat_rotate
from ..types import IDENTITY_QUAT, BodySpec, CompiledWorld, JointKind, JointSpec, Motion, ShapeKind, Surface
from ._colliders import Prisms
from ._options import OdeOptions
from ._shapes import FrameOffset, build_robot_geoms, check_static_shapes, is_robot_body

#: A kinematic body's mass relative to the heaviest dynamic body (at least 1 kg): dynamic bodies push it
#: by m/M of their impulse during a step, and the backend re-places it exactly afterwards anyway.
KINEMATIC_MASS_RATIO = 1e6
#: Category bits: which geoms may collide (ODE tests a pair when (cat1 & col2) or (cat2 & col1)).
CAT_STATIC, CAT_KINEMATIC, CAT_DYNAMIC = 1, 2, 4
_BITS = {
    Motion.STATIC: (CAT_STATIC, CAT_DYNAMIC),
    Motion.KINEMATIC: (CAT_KINEMATIC, CAT_DYNAMIC),
    Motion.DYNAMIC: (CAT_DYNAMIC, CAT_STATIC | CAT_KINEMATIC | CAT_DYNAMIC),
}
#: panda3d's surface table is indexed by a PN_uint8.
MAX_SURFACE_CLASSES = 255


@dataclass
class JointHandle:
    """One scenario joint and the ODE joint that realises it."""

    spec: JointSpec
    joint: Any  # OdeSliderJoint | OdeHingeJoint | OdeBallJoint | OdeFixedJoint | OdeUniversalJoint
    body: OdeBody
    feedback: OdeJointFeedback | None  # motorised kinds only
    vel: float = 0.0
    fmax: float = 0.0


@dataclass
class Scene:
    world: OdeWorld
    space: Any  # OdeSimpleSpace | OdeHashSpace
    contact_group: OdeJointGroup
    bodies: list[OdeBody | None]  # None: static (a bodiless geom)
    geoms: list[Any]
    geom_index: dict[int, int]  # hash(geom.getId()) (the dGeomID) -> body index
    joints: list[JointHandle]
    surface_class: list[int]  # per body: its row in the surface table
    surfaces: dict[tuple[int, int], Surface] = field(default_factory=dict)  # (class, class), both orders
    #: body index pairs that never touch (CompiledWorld.excluded_pairs), both orders
    excluded: frozenset[tuple[int, int]] = frozenset()
    #: per body with a COM offset: where its COM sits in its frame (the OdeBody is at the COM)
    offsets: dict[int, FrameOffset] = field(default_factory=dict)
    meshes: dict[int, Any] = field(default_factory=dict)  # id(Mesh) -> OdeTriMeshData, kept alive
    #: hash(geom.getId()) of the shapes' triangle-mesh geoms (hulls, static meshes; no prism stand-in): their
    #: pairs keep at most four contacts (_manifold)
    mesh_geoms: frozenset[int] = frozenset()


def panda_quat(q: tuple[float, float, float, float]) -> Quat:
    """panda3d's Quat is (r, i, j, k) = (w, x, y, z), the project's order."""
    return Quat(q[0], q[1], q[2], q[3])


def _mass(spec: BodySpec, kinematic_mass: float) -> OdeMass:
    mass = OdeMass()
    if spec.motion is Motion.KINEMATIC:
        shape, m = spec.shape, kinematic_mass
        if is_robot_body(spec):  # any inertia will do under a huge mass: a 1 m cube's
            mass.setBoxTotal(m, 1.0, 1.0, 1.0)
        elif shape.kind is ShapeKind.BOX:
            mass.setBoxTotal(m, *(max(s, 1e-3) for s in shape.size))
        elif shape.kind is ShapeKind.SPHERE:
            mass.setSphereTotal(m, shape.radius)
        elif shape.kind is ShapeKind.CAPSULE:
            mass.setCapsuleTotal(m, 3, shape.radius, shape.length)
        else:
            mass.setCylinderTotal(m, 3, shape.radius, shape.length)
        return mass
    if not spec.mass > 0.0 or not all(i > 0.0 for i in spec.inertia):
        raise UnsupportedFeature(f"Dynamic body `{spec.name}` needs a positive mass and inertia.")
    if spec.inertia_quat != IDENTITY_QUAT:  # the full tensor in the body frame (the OdeBody's orientation)
        t = spec.inertia_tensor()
        mass.setParameters(spec.mass, 0.0, 0.0, 0.0, t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2])
        return mass
    ixx, iyy, izz = spec.inertia
    mass.setParameters(spec.mass, 0.0, 0.0, 0.0, ixx, iyy, izz, 0.0, 0.0, 0.0)
    return mass


def _geom(space: Any, spec: BodySpec) -> Any:
    shape = spec.shape
    if shape.kind is ShapeKind.BOX:
        return OdeBoxGeom(space, *shape.size)
    if shape.kind is ShapeKind.SPHERE:
        return OdeSphereGeom(space, shape.radius)
    if shape.kind is ShapeKind.CAPSULE:  # ODE's capsule and cylinder lie along local z, as the world's
        return OdeCappedCylinderGeom(space, shape.radius, shape.length)
    if shape.kind is ShapeKind.CYLINDER:
        return OdeCylinderGeom(space, shape.radius, shape.length)
    if spec.motion is not Motion.STATIC:
        raise UnsupportedFeature(f"Plane `{spec.name}` must be static (ODE planes are non-placeable).")
    n = quat_rotate(spec.quat, (0.0, 0.0, 1.0))  # the body's local +z, through its position
    d = n[0] * spec.pos[0] + n[1] * spec.pos[1] + n[2] * spec.pos[2]
    return OdePlaneGeom(space, n[0], n[1], n[2], d)


def _surface_classes(world: CompiledWorld) -> tuple[list[int], dict[tuple[int, int], Surface]]:
    """Class 0 for bodies in no pair override, one class each for the others; the surface per class pair."""
    named = sorted({world.body_index(n) for p in world.pair_surfaces for n in (p.a, p.b)})
    classes = [0] * len(world.bodies)
    for k, index in enumerate(named, start=1):
        classes[index] = k
    representative = [None, *named]  # a body of each class (class 0: any body in no override)
    table: dict[tuple[int, int], Surface] = {}
    for i, bi in enumerate(representative):
        for j, bj in enumerate(representative):
            if bi is None or bj is None:
                table[(i, j)] = world.default_surface
            else:
                table[(i, j)] = world.surface(world.bodies[bi].name, world.bodies[bj].name)
    return classes, table


def _joint(world: OdeWorld, spec: JointSpec, body: OdeBody, other: OdeBody | None) -> JointHandle:
    feedback: OdeJointFeedback | None = None
    if spec.kind is JointKind.SLIDER:
        joint: Any = OdeSliderJoint(world)
        joint.attach(body, other)
        joint.setAxis(*spec.axis)  # after attach: ODE zeroes the position at this configuration
    elif spec.kind is JointKind.HINGE:
        joint = OdeHingeJoint(world)
        joint.attach(body, other)
        joint.setAnchor(*spec.anchor)
        joint.setAxis(*spec.axis)
    elif spec.kind is JointKind.UNIVERSAL:
        if spec.axis2 is None:
            raise UnsupportedFeature(f"Universal joint `{spec.name}` needs axis2.")
        joint = OdeUniversalJoint(world)
        joint.attach(body, other)
        joint.setAnchor(*spec.anchor)
        joint.setAxis1(*spec.axis)
        joint.setAxis2(*spec.axis2)
    elif spec.kind is JointKind.BALL:
        joint = OdeBallJoint(world)
        joint.attach(body, other)
        joint.setAnchor(*spec.anchor)
    else:
        joint = OdeFixedJoint(world)
        joint.attach(body, other)
        joint.set()
    handle = JointHandle(spec, joint, body, feedback)
    if spec.kind in (JointKind.SLIDER, JointKind.HINGE, JointKind.UNIVERSAL):
        handle.feedback = OdeJointFeedback()
        joint.setFeedback(handle.feedback)  # Python owns it: ODE never frees feedback structs
        if spec.lo is not None:
            joint.setParamLoStop(*axis_arg(handle), spec.lo)
        if spec.hi is not None:
            joint.setParamHiStop(*axis_arg(handle), spec.hi)
        if spec.motor is not None:
            set_motor(handle, spec.motor.vel, spec.motor.fmax)
    elif spec.motor is not None or spec.lo is not None or spec.hi is not None:
        raise UnsupportedFeature(f"Joint `{spec.name}` ({spec.kind.value}) has no motor or stops in ODE.")
    return handle


def axis_arg(handle: JointHandle) -> tuple[int, ...]:
    """panda3d's universal-joint params take the axis first (0: the first axis, the joint's coordinate)."""
    return (0,) if handle.spec.kind is JointKind.UNIVERSAL else ()


def set_motor(handle: JointHandle, vel: float, fmax: float) -> None:
    """ODE's velocity motor: dParamVel and dParamFMax (fmax 0 switches it off)."""
    if handle.feedback is None:
        raise UnsupportedFeature(f"Joint `{handle.spec.name}` ({handle.spec.kind.value}) has no motor.")
    if not (math.isfinite(vel) and math.isfinite(fmax) and fmax >= 0.0):
        raise UnsupportedFeature(f"Invalid motor for joint `{handle.spec.name}`: vel={vel!r}, fmax={fmax!r}.")
    handle.joint.setParamVel(*axis_arg(handle), vel)
    handle.joint.setParamFMax(*axis_arg(handle), fmax)
    handle.vel, handle.fmax = vel, fmax


def build_scene(world: CompiledWorld, options: OdeOptions) -> Scene:
    ode_world = OdeWorld()
    ode_world.setGravity(*world.gravity)
    ode_world.setErp(options.erp)
    ode_world.setCfm(options.cfm)
    ode_world.setContactMaxCorrectingVel(options.max_correcting_vel)
    ode_world.setQuickStepNumIterations(options.quickstep_iterations)
    space = OdeSimpleSpace() if options.space == "simple" else OdeHashSpace()
    heaviest = max([b.mass for b in world.bodies if b.motion is Motion.DYNAMIC] + [1.0])
    kinematic_mass = KINEMATIC_MASS_RATIO * heaviest

    bodies: list[OdeBody | None] = []
    geoms: list[Any] = []
    geom_body: list[int] = []  # per geom: its body's index
    offsets: dict[int, FrameOffset] = {}
    meshes: dict[int, Any] = {}
    mesh_geoms: set[int] = set()
    prisms = Prisms(world, meshes)
    for index, spec in enumerate(world.bodies):
        robot = is_robot_body(spec)
        body: OdeBody | None = None
        if spec.motion is not Motion.STATIC:
            body = OdeBody(ode_world)
            body.setMass(_mass(spec, kinematic_mass))
            pos, lin_vel = spec.pos, spec.lin_vel
            if spec.com != (0.0, 0.0, 0.0):  # the OdeBody sits at the COM
                offsets[index] = offset = FrameOffset(np.asarray(spec.com, dtype=float))
                pos = offset.com_pose(spec.pos, spec.quat)
                lin_vel = offset.com_velocity(spec.quat, spec.lin_vel, spec.ang_vel)
            body.setPosition(*pos)
            body.setQuaternion(panda_quat(spec.quat))
            body.setLinearVel(*lin_vel)
            body.setAngularVel(*spec.ang_vel)
            if spec.motion is Motion.KINEMATIC:
                body.setGravityMode(False)
        if robot:
            check_static_shapes(spec)
            body_geoms = build_robot_geoms(space, spec, body, meshes)
        else:
            geom = _geom(space, spec)
            if body is not None:
                geom.setBody(body)
            elif spec.shape.kind is not ShapeKind.PLANE:
                geom.setPosition(*spec.pos)
                geom.setQuaternion(panda_quat(spec.quat))
            body_geoms = [geom]
        category, collide = _BITS[spec.motion]
        for geom in body_geoms:
            geom.setCategoryBits(BitMask32(category))
            geom.setCollideBits(BitMask32(collide))
        mesh_geoms.update(hash(g.getId()) for g in body_geoms if isinstance(g, OdeTriMeshGeom))
        body_geoms += prisms.add(space, index, spec, body_geoms, body)  # capsule-cylinder (_colliders)
        bodies.append(body)
        geoms.extend(body_geoms)
        geom_body.extend([index] * len(body_geoms))

    joints: list[JointHandle] = []
    for jspec in world.joints:
        body = bodies[world.body_index(jspec.body)]
        if body is None:
            raise UnsupportedFeature(f"Joint `{jspec.name}`: its body `{jspec.body}` is static.")
        other = None if jspec.other is None else bodies[world.body_index(jspec.other)]  # static = environment
        joints.append(_joint(ode_world, jspec, body, other))

    classes, table = _surface_classes(world)
    return Scene(
        world=ode_world,
        space=space,
        contact_group=OdeJointGroup(),
        bodies=bodies,
        geoms=geoms,
        geom_index={hash(g.getId()): i for g, i in zip(geoms, geom_body, strict=True)},
        joints=joints,
        surface_class=classes,
        surfaces=table,
        excluded=_excluded(world),
        offsets=offsets,
        meshes=meshes,
        mesh_geoms=frozenset(mesh_geoms),
    )


def _excluded(world: CompiledWorld) -> frozenset[tuple[int, int]]:
    pairs = [(world.body_index(a), world.body_index(b)) for a, b in world.excluded_pairs]
    return frozenset(pairs + [(j, i) for i, j in pairs])


def destroy_scene(scene: Scene) -> None:
    """panda3d's wrappers never free ODE objects on their own: destroy them, contacts first."""
    scene.contact_group.empty()
    scene.contact_group.destroy()
    for handle in scene.joints:
        handle.joint.destroy()
    for geom in scene.geoms:
        geom.destroy()
    for data in scene.meshes.values():
        data.destroy()
    for body in scene.bodies:
        if body is not None:
            body.destroy()
    scene.space.destroy()
    scene.world.destroy()
