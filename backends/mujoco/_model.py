"""Building the MuJoCo model of a CompiledWorld with ``mujoco.MjSpec`` (no XML).

Bodies become one kinematic tree: a body joined to the environment (or to a static body) is a child of
the world body with a slide/hinge/ball joint (a fixed joint: no joint, welded); a body joined to another
body is that body's child; every other dynamic body, and every kinematic body, is a free root. A joint is
attached to whichever end the tree reaches second, so its MuJoCo coordinate may be the negative of the
world's (``Edge.sign``). Closed loops are not representable and are refused.

Contacts come from MuJoCo's own collision filtering, so building costs O(bodies), not O(bodies^2):
bodies that can touch (a dynamic rigid group and anything not in it) pass the geoms' contype/conaffinity
bits, joined bodies are excluded pairs (parent filtering off, so a body also touches its parent's rigid
group, as in ODE), and every geom carries the world's surface, which MuJoCo's combination of two equal
geoms (max, solmix mean of equal values, min of direct solrefs) leaves exactly as it is. Only a pair with
a surface of its own gets an explicit contact pair. The normal row follows ODE's
velocity-level contact rather than MuJoCo's spring-damper default: with a constant impedance ``d`` a
row reaches ``a = -B*v - K*r + (1-d)*a0`` (``solref = (-K, -B)``), so ``B = (1+e)/h`` turns the approach
speed ``v`` into ``-e*v`` in one engine step ``h`` (ODE's bounce) and ``K = erp/h**2`` removes ``erp`` of
the penetration per step (ODE's ERP). Friction rows (``solreffriction = (-1, -1/h)``) remove the slip in
one step, as ODE's friction rows do; a geom's contacts have no friction solref of their own (MuJoCo
uses the normal one), so when it differs (bounce) ``_coulomb.step`` sets their friction rows' reference
(``Layout.friction_damping``), and it keeps MuJoCo's convex cone from turning the slip a sliding contact
cannot remove into a separating push. docs/backends/mujoco.md gives the measured consequences. The geoms,
their contact parameters and the explicit pairs: ``_geoms``.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from ..errors import EngineFailure, UnsupportedFeature
from ..geometry import quat_conj, quat_mul, quat_rotate
from ..types import BodySpec, CompiledWorld, Fluid, JointKind, Motion
from . import _native
from ._filters import add_excludes
from ._geoms import IMPEDANCE, SOLIMP, ContactParams, add_geoms, add_pairs, contact_params
from ._native import NativeModel
from ._options import MujocoOptions

#: Impedance of the motor rows: the rate error left after a step that reaches the target is 1e-4 of it.
MOTOR_IMPEDANCE = 0.9999
#: A kinematic body is a free body this much heavier than the heaviest dynamic body (at least 1 kg),
#: with gravity compensated and its pose and velocity imposed before every engine step.
KINEMATIC_MASS_RATIO = 1e6

_JOINT = {
    JointKind.SLIDER: mujoco.mjtJoint.mjJNT_SLIDE,
    JointKind.HINGE: mujoco.mjtJoint.mjJNT_HINGE,
    JointKind.BALL: mujoco.mjtJoint.mjJNT_BALL,
}


@dataclass(frozen=True)
class Edge:
    """How a body hangs in the MuJoCo tree."""

    parent: str | None  # None: the world body
    joint: int | None  # index into world.joints; None: a free root, or a static body
    sign: float  # +1: the MuJoCo joint coordinate is the world joint's, -1: its negative


@dataclass
class Layout:
    """The compiled model and the index maps between it and the CompiledWorld."""

    model: mujoco.MjModel
    edges: dict[str, Edge]
    body_id: np.ndarray  # world body index -> MuJoCo body id
    geom_body: np.ndarray  # MuJoCo geom id -> world body index
    joint_id: np.ndarray  # world joint index -> MuJoCo joint id, -1 for a fixed joint
    motor_id: np.ndarray  # world joint index -> MuJoCo tendon id of its motor, -1 when it has none
    helper_dof: np.ndarray  # world joint index -> dof of its motor's helper slide, -1 when none
    #: B of the friction rows of contacts made from geoms (``aref = -B*v``), or None when the geoms'
    #: solref already gives it (no bounce): see ``_coulomb.step``
    friction_damping: float | None = None


def plan_tree(world: CompiledWorld, native: NativeModel | None = None) -> dict[str, Edge]:
    """Every body's place in the tree, parents before children (static bodies first); the bodies and joints
    of a robot built from its file (``native``) are the file's, not planned here."""
    motion = {b.name: b.motion for b in world.bodies}
    if native is not None:
        world = _native.without_file(world, native)

    def node(name: str | None) -> str | None:  # static bodies are the environment
        return None if name is None or motion[name] is Motion.STATIC else name

    links: dict[str | None, list[int]] = {None: [], **{b.name: [] for b in world.bodies}}
    for i, joint in enumerate(world.joints):
        if joint.kind not in _JOINT and joint.kind is not JointKind.FIXED:
            raise UnsupportedFeature(f"mujoco: joint `{joint.name}` is {joint.kind.value}, not supported")
        a, b = node(joint.body), node(joint.other)
        if a == b:
            raise UnsupportedFeature(f"mujoco: joint `{joint.name}` joins nothing that can move")
        links[a].append(i)
        links[b].append(i)
    edges = {b.name: Edge(None, None, 1.0) for b in world.bodies if b.motion is Motion.STATIC}
    roots = [b.name for b in world.bodies if b.motion is Motion.KINEMATIC]
    roots += [b.name for b in world.bodies if b.motion is Motion.DYNAMIC]
    for root in [None, *roots]:
        if root is not None:
            if root in edges:
                continue
            edges[root] = Edge(None, None, 1.0)
        queue: deque[str | None] = deque([root])
        while queue:
            parent = queue.popleft()
            for i in links[parent]:
                joint = world.joints[i]
                if parent is not None and edges[parent].joint == i:
                    continue  # the joint that hangs `parent` itself
                a, b = node(joint.body), node(joint.other)
                child = b if a == parent else a
                if child is None or child in edges:
                    raise UnsupportedFeature(f"mujoco: joint `{joint.name}` closes a kinematic loop")
                if motion[child] is Motion.KINEMATIC:
                    raise UnsupportedFeature(f"mujoco: kinematic body `{child}` cannot hang from joint `{joint.name}`")
                edges[child] = Edge(parent, i, 1.0 if child == a else -1.0)
                queue.append(child)
    return edges


def _rigid_groups(world: CompiledWorld, edges: dict[str, Edge]) -> dict[str, str]:
    """Body -> the first body up its chain of fixed joints ("" when the chain ends at the world)."""
    group: dict[str, str] = {}
    motion = {b.name: b.motion for b in world.bodies}
    for name, edge in edges.items():  # parents come first
        fixed = edge.joint is not None and world.joints[edge.joint].kind is JointKind.FIXED
        if fixed:
            group[name] = group[edge.parent] if edge.parent is not None else ""
        else:
            group[name] = "" if motion[name] is Motion.STATIC else name
    return group


def build(world: CompiledWorld, opts: MujocoOptions, h: float) -> Layout:
    """Compile ``world`` with engine step ``h``."""
    native = _native.load(world)
    edges = plan_tree(world, native)
    spec = mujoco.MjSpec()  # the scenario's parts (attached to an MJCF robot's own spec, _native)
    spec.compiler.degree = False  # hinge ranges in radians
    specs = {b.name: b for b in world.bodies}
    heavy = KINEMATIC_MASS_RATIO * max([1.0] + [b.mass for b in world.bodies if b.motion is Motion.DYNAMIC])
    mj_bodies: dict[str, Any] = {}
    geoms: dict[str, list[str]] = {}  # body -> its geoms' names
    group = _rigid_groups(world, edges)
    moving = {b.name for b in world.bodies if b.motion is Motion.DYNAMIC}  # rigid groups that move freely
    default = contact_params(world.default_surface, h, opts)
    for name, edge in edges.items():
        body = specs[name]
        parent = specs[edge.parent] if edge.parent is not None else None
        mj = (mj_bodies[edge.parent] if edge.parent is not None else spec.worldbody).add_body(
            name=f"body:{name}", **_relative_pose(body, parent)
        )
        mj_bodies[name] = mj
        if body.motion is Motion.KINEMATIC:  # its motion is imposed: the inertial frame does not matter
            mj.mass, mj.inertia, mj.explicitinertial = heavy, [heavy] * 3, True
            mj.ipos, mj.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
            mj.gravcomp = 1.0
        elif body.motion is Motion.DYNAMIC:  # the inertial frame: COM at `com`, principal axes `inertia_quat`
            mj.mass, mj.inertia, mj.explicitinertial = body.mass, list(body.inertia), True
            mj.ipos, mj.iquat = list(body.com), list(body.inertia_quat)
            mj.gravcomp = 0.0
        if body.motion is not Motion.STATIC and edge.joint is None:
            mj.add_freejoint()
        elif edge.joint is not None:
            _add_joint(mj, body, world, edge, h, opts)
        if native is not None and name == native.world_link:
            geoms[name] = native.geoms[name]  # the file's world geoms; this body only marks the placement
            continue
        geoms[name] = add_geoms(spec, mj, body, default, group[name] in moving)
    names = _native.Names(native)
    _add_motors(spec, world, heavy, h, names)
    _add_mimics(spec, world, edges, h, opts, native)
    if native is not None:
        geoms.update({b: native.geoms[b] for b in native.bodies})
        group.update({b: b for b in native.bodies})
        for b in native.bodies:  # the file's own bodies touch as MuJoCo's filtering says
            moving.add(b)
    add_excludes(spec, world, group, moving, names)
    add_pairs(spec, world, group, moving, geoms, default, h, opts)
    top = spec
    with _native.unprefixed():
        if native is not None:
            if not world.model_options:
                _native.set_geom_surfaces(native, default, SOLIMP)
                _native.drop_contact_flag(native)
            top = _native.attach(native, spec)
        if native is None or not world.model_options:
            _native.clear_flags(top)
            _set_options(top, world, h)
        model = _compile(top, len(world.bodies))
    if native is not None:
        _native.scale_total_mass(model, native)
        _native.apply_limits(model, world, native)
    if not world.model_options:
        _rescale_solver(model, [names.body(b.name) for b in world.bodies if b.motion is Motion.DYNAMIC])
    body_ids = np.array([model.body(names.body(b.name)).id for b in world.bodies], dtype=np.int64)
    owner = np.full(model.nbody, -1, dtype=np.int64)  # MuJoCo body -> world body
    owner[body_ids] = np.arange(len(world.bodies))
    if native is not None:
        owner[0] = world.body_index(native.world_link)  # the file's world geoms
    motored = [_motorised(j.kind) and names.has_motor(j) for j in world.joints]
    return Layout(
        model=model,
        edges=edges,
        body_id=body_ids,
        geom_body=owner[model.geom_bodyid],
        joint_id=np.array(
            [model.joint(names.joint(j.name)).id if j.kind in _JOINT else -1 for j in world.joints], dtype=np.int64
        ),
        motor_id=np.array(
            [model.tendon(f"motor:{j.name}").id if m else -1 for j, m in zip(world.joints, motored, strict=True)],
            dtype=np.int64,
        ),
        helper_dof=np.array(
            [
                model.jnt_dofadr[model.joint(f"helper:{j.name}").id] if m else -1
                for j, m in zip(world.joints, motored, strict=True)
            ],
            dtype=np.int64,
        ),  # fmt: skip
        friction_damping=None if world.model_options else _friction_damping(default),
    )


def _set_options(spec: Any, world: CompiledWorld, h: float) -> None:
    """The backend's own options (ODE's semantics; docs/backends/mujoco.md)."""
    spec.option.timestep = h
    spec.option.gravity = list(world.gravity)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.tolerance = 1e-10  # motors settle to 1e-6 of their target rate (default 1e-8: 2e-4)
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET  # a blow-up must surface
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_FILTERPARENT  # joined pairs are excluded instead
    fluid = world.fluid if world.fluid is not None else Fluid()  # the scenario's or the file's (CompiledWorld.fluid)
    spec.option.density, spec.option.viscosity, spec.option.wind = fluid.density, fluid.viscosity, list(fluid.wind)


#: Arena (MjData's contacts, constraints and scratch stack) when MuJoCo's default cannot be allocated:
#: this per body, plus 8 bytes per pair of bodies (mj_collision's broadphase keeps two int arrays of
#: N(N-1)/2 pairs on the stack: 4 bytes per pair of bodies, doubled for the margin), plus a floor.
ARENA_PER_BODY, ARENA_FLOOR = 64 * 1024, 64 * 1024 * 1024


def _compile(spec: Any, bodies: int) -> mujoco.MjModel:
    """``spec.compile()``; MuJoCo's default arena grows faster than the bodies (1.7 GB at 1,000 boxes, only
    reserved) and cannot be allocated at 10,000, so such a model gets an arena sized by ``ARENA_*``."""
    try:
        return spec.compile()
    except ValueError as exc:  # MjSpec reports a model it refuses as ValueError("Error: ...")
        if "allocate memory" not in str(exc):
            raise EngineFailure(f"mujoco: MjSpec.compile refused the model: {exc}", backend="mujoco") from exc
    spec.memory = ARENA_FLOOR + ARENA_PER_BODY * bodies + 8 * bodies * bodies
    try:
        return spec.compile()
    except ValueError as exc:
        raise EngineFailure(f"mujoco: MjSpec.compile refused the model: {exc}", backend="mujoco") from exc


def _friction_damping(default: ContactParams) -> float | None:
    """``Layout.friction_damping``: MuJoCo's ``B = -solref[1]/dmax`` of the friction solref, when the
    geoms' (normal) solref gives the friction rows another one."""
    if default.solref[1] == default.solreffriction[1]:
        return None  # the K terms differ but act on the friction rows' position, which is 0
    return -default.solreffriction[1] / IMPEDANCE


def _rescale_solver(model: mujoco.MjModel, dynamic: list[str]) -> None:  # MuJoCo body names
    """Base the solver's tolerance on the dynamic bodies' inertia, not on the heavy driven bodies.

    MuJoCo scales its convergence test by ``stat.meaninertia``, the mean diagonal of the mass matrix;
    the kinematic bodies and motor helpers would inflate it a millionfold and stop the solver early.
    """
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    ids = [model.body(name).id for name in dynamic]
    dofs = np.flatnonzero(np.isin(model.dof_bodyid, ids))
    if dofs.size:
        diagonal = data.M[model.M_rowadr + model.M_rownnz - 1]  # CSR rows end on the diagonal
        model.stat.meaninertia = float(np.mean(diagonal[dofs]))


def _motorised(kind: JointKind) -> bool:
    return kind in (JointKind.SLIDER, JointKind.HINGE)


def _relative_pose(body: BodySpec, parent: BodySpec | None) -> dict[str, list[float]]:
    if parent is None:
        return {"pos": list(body.pos), "quat": list(body.quat)}
    inv = quat_conj(parent.quat)
    delta = [body.pos[k] - parent.pos[k] for k in range(3)]
    return {"pos": list(quat_rotate(inv, delta)), "quat": list(quat_mul(inv, body.quat))}


def _add_joint(mj: Any, body: BodySpec, world: CompiledWorld, edge: Edge, h: float, opts: MujocoOptions) -> None:
    joint = world.joints[edge.joint]  # type: ignore[index]
    if joint.kind is JointKind.FIXED:
        return  # no joint: welded to the parent
    inv = quat_conj(body.quat)
    anchor = [joint.anchor[k] - body.pos[k] for k in range(3)]
    mj_joint = mj.add_joint(
        name=f"joint:{joint.name}",
        type=_JOINT[joint.kind],
        axis=list(quat_rotate(inv, joint.axis)),
        pos=list(quat_rotate(inv, anchor)),
    )
    mj_joint.armature = joint.dynamics.armature  # dof_armature (joint:armature)
    if joint.dynamics.stiffness > 0:  # a spring MuJoCo applies itself (joint:stiffness); the coordinate's 0 is
        mj_joint.stiffness = joint.dynamics.stiffness  # the start pose, as JointSpec's
        mj_joint.springref = edge.sign * joint.dynamics.springref
    if joint.lo is None and joint.hi is None:
        return
    if joint.kind is JointKind.BALL:
        raise UnsupportedFeature(f"mujoco: stops on ball joint `{joint.name}` are not supported")
    lo = -math.inf if joint.lo is None else joint.lo
    hi = math.inf if joint.hi is None else joint.hi
    mj_joint.range = sorted([edge.sign * lo, edge.sign * hi])
    mj_joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    mj_joint.solref_limit = [-opts.erp / h**2, -1.0 / h]  # ODE's stop: no bounce, ERP correction
    mj_joint.solimp_limit = SOLIMP


def _add_mimics(
    spec: Any, world: CompiledWorld, edges: dict[str, Edge], h: float, opts: MujocoOptions, native: NativeModel | None
) -> None:
    """Each coupling (URDF `<mimic>`, ``joint:mimic``) as MuJoCo's URDF importer and MJCF write it: a joint
    equality ``q1 - q1_0 = polycoef(q2 - q2_0)`` with polycoef (offset, multiplier) in MuJoCo's coordinates
    (the edge's sign x the world's; qpos0 is the start, as for every joint here), as stiff as a joint's stop
    (ODE's ERP correction), so a coupling and a stop hold alike. A coupling of an MJCF robot's joints is the
    file's own `<equality>` (runner.language.mjcf_needs), which MuJoCo reads with the file: not added again."""
    sign = {edge.joint: edge.sign for edge in edges.values() if edge.joint is not None}
    index = {joint.name: k for k, joint in enumerate(world.joints)}
    for coupling in world.couplings:
        if native is not None and coupling.joint in native.joints:
            continue
        ratio, offset = coupling.engine_terms(sign[index[coupling.joint]], sign[index[coupling.leader]])
        data = [0.0] * mujoco.mjNEQDATA
        data[0], data[1] = offset, ratio
        spec.add_equality(
            type=mujoco.mjtEq.mjEQ_JOINT,
            name=f"mimic:{coupling.joint}",
            name1=f"joint:{coupling.joint}",
            name2=f"joint:{coupling.leader}",
            data=data,
            solref=[-opts.erp / h**2, -1.0 / h],
            solimp=SOLIMP,
        )


def _add_motors(spec: Any, world: CompiledWorld, heavy: float, h: float, names: _native.Names) -> None:
    """ODE's velocity motor as a bounded velocity constraint: a tendon's frictionloss row.

    The tendon measures the joint's rate minus the rate of a heavy helper slide whose velocity the
    backend sets to the target, so the frictionloss row drives the joint to the target with a force
    bounded by fmax (the tendon's frictionloss), in one step when fmax allows, as ODE's LCP does. A
    velocity actuator with a large gain chatters by one step of acceleration around the target instead:
    MuJoCo drops a clamped actuator's implicit damping, so the step that crosses the target overshoots.
    """
    for joint in world.joints:
        if not (_motorised(joint.kind) and names.has_motor(joint)):
            continue
        helper = spec.worldbody.add_body(name=f"motor:{joint.name}", mass=heavy, inertia=[heavy] * 3)
        helper.explicitinertial, helper.gravcomp = True, 1.0
        helper.ipos, helper.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
        helper.add_joint(name=f"helper:{joint.name}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1.0, 0.0, 0.0])
        tendon = spec.add_tendon(name=f"motor:{joint.name}")
        tendon.wrap_joint(names.joint(joint.name), 1.0)
        tendon.wrap_joint(f"helper:{joint.name}", -1.0)
        tendon.solref_friction = [-1.0, -1.0 / h]  # the rate error is removed in one step
        tendon.solimp_friction = [MOTOR_IMPEDANCE, MOTOR_IMPEDANCE, 0.001, 0.5, 2.0]
        tendon.frictionloss = 0.0  # fmax; the backend sets it (0: off)
