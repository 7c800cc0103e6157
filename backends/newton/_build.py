"""A CompiledWorld as a Newton ``Model`` (docs/backends/newton.md, "Mapping").

* Static bodies are shapes on Newton's world (body -1) at their world poses; a plane is an infinite
  ``add_shape_plane`` (its normal the body's local +z).
* Moving bodies are Newton bodies with the world's mass, COM and full inertia tensor (the shapes carry density
  0, so they add nothing). A body in no joint is ``add_body`` (a free joint); jointed bodies are links of the
  articulations of ``_tree.groups``. Kinematic bodies are ``is_kinematic`` roots, posed by the adapter.
* Joints sit at the anchor with the world's orientation at the start (so every coordinate starts at 0):
  slider -> prismatic, hinge -> revolute, ball, fixed; stops are the joint limits. No Newton drive: the ODE
  velocity motor is the adapter's (a generalised force clamped to fmax, ``_motors.py``).
* Friction and restitution per body from ``_surfaces.solve`` (Newton takes the mean of two shapes); no
  torsional or rolling friction (ODE has none).
* Collision filters: every shape pair of bodies that cannot touch (``touching_pairs``' complement).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._kit.pairs import touching_pairs
from ..errors import UnsupportedFeature
from ..geometry import quat_matrices
from ..types import BodySpec, CompiledWorld, JointKind, JointSpec, Motion, Shape, ShapeKind
from . import _surfaces, _tree
from ._options import NewtonOptions

#: How far apart two shapes may be at the start of an engine step and still be a contact of that step (Newton's
#: ``ShapeConfig.gap``; its default, 0.1 m, let XPBD catch a falling ball the step before it reached the plane:
#: XPBD acts on contacts at the positions predicted for the end of the step). 0 is ODE's rule, but a body XPBD
#: has projected exactly onto its support is then not in contact at the next step and falls for one (a capsule
#: at rest hopped at g h); 0.1 mm holds bodies at rest and is under one step's fall at the suite's impacts.
CONTACT_GAP = 1e-4


@dataclass(frozen=True)
class JointHandle:
    spec: JointSpec
    index: int  # Newton's joint index
    parent: int | None  # world body index (None: the world)
    child: int
    sign: float  # the world's coordinate = sign * Newton's
    q: int  # the joint's first coordinate in joint_q (and joint_qd)


@dataclass
class Built:
    model: Any
    body: list[int]  # per world body: Newton's body index, -1 for static bodies
    shape_owner: np.ndarray  # per Newton shape: the world body index
    joints: list[JointHandle]
    surfaces: _surfaces.BodySurfaces


def check(world: CompiledWorld) -> None:
    """What the build would refuse, judged without the engine."""
    _tree.groups(world)
    _surfaces.solve(world)
    for body in world.bodies:
        if body.motion is Motion.DYNAMIC and body.mass <= 0.0:
            raise UnsupportedFeature(f"Backend `newton` needs a positive mass on moving body `{body.name}`.")
        for placed in body.placed_shapes():
            if placed.shape.kind is ShapeKind.PLANE and body.motion is not Motion.STATIC:
                raise UnsupportedFeature(f"Backend `newton`: plane `{body.name}` must be static.")


def xyzw(quat: Any) -> tuple[float, float, float, float]:
    """A (w, x, y, z) quaternion, normalised, in Newton's (x, y, z, w) order."""
    w, x, y, z = (float(v) for v in quat)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    return (x / n, y / n, z / n, w / n)


def rotate_xyzw(q_xyzw: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` rotated by a Newton quaternion (x, y, z, w)."""
    x, y, z, w = (float(c) for c in q_xyzw)
    return np.asarray(quat_matrices((w, x, y, z)) @ np.asarray(v, dtype=float))


def build(wp: Any, newton: Any, world: CompiledWorld, options: NewtonOptions, device: str) -> Built:
    """The finalized model of ``world`` on ``device``."""
    check(world)
    surfaces = _surfaces.solve(world)
    builder = newton.ModelBuilder(up_axis=newton.Axis.Z, gravity=tuple(float(g) for g in world.gravity))
    groups = _tree.groups(world)
    jointed = {o.child for g in groups for o in g.joints} | {g.root for g in groups if g.root is not None}
    body: list[int] = []
    owner: list[int] = []
    shapes: list[list[int]] = []
    for i, spec in enumerate(world.bodies):
        if spec.motion is Motion.STATIC:
            body.append(-1)
        else:
            xform = wp.transform(wp.vec3(*spec.pos), wp.quat(*xyzw(spec.quat)))
            kwargs = {
                "xform": xform,
                "mass": spec.mass if spec.mass > 0 else 1.0,
                "com": wp.vec3(*spec.com),
                "inertia": wp.mat33(*_inertia(spec).ravel()),
                "label": spec.name,
                "is_kinematic": spec.motion is Motion.KINEMATIC,
                "lock_inertia": True,
            }
            body.append(builder.add_link(**kwargs) if i in jointed else builder.add_body(**kwargs))
        ids = []
        for placed in spec.placed_shapes():
            cfg = newton.ModelBuilder.ShapeConfig(
                density=0.0, mu=surfaces.mu[i], restitution=surfaces.restitution[i], mu_torsional=0.0,
                mu_rolling=0.0, ke=options.contact_stiffness, kd=_damping(options.contact_stiffness, spec),
                gap=CONTACT_GAP,
            )  # fmt: skip
            ids.append(_shape(wp, newton, builder, body[i], spec, placed.shape, placed.pos, placed.quat, cfg))
            owner.append(i)
        shapes.append(ids)
    handles = _joints(wp, newton, builder, world, groups, body, options)
    _filters(world, builder, shapes)
    model = builder.finalize(device=device)
    q_start = model.joint_q_start.numpy()
    handles = [JointHandle(h.spec, h.index, h.parent, h.child, h.sign, int(q_start[h.index])) for h in handles]
    return Built(model, body, np.asarray(owner, dtype=np.int64), handles, surfaces)


def _damping(stiffness: float, spec: BodySpec) -> float:
    """Featherstone's penalty contact damping: critical for the body's mass on the stiffness (ignored by XPBD)."""
    return 2.0 * math.sqrt(stiffness * max(spec.mass, 1e-6))


def _inertia(spec: BodySpec) -> np.ndarray:
    if spec.motion is Motion.KINEMATIC and spec.mass <= 0:
        return np.eye(3)
    return spec.inertia_tensor()


def _shape(wp: Any, newton: Any, builder: Any, body: int, spec: BodySpec, shape: Shape, pos: Any, quat: Any,
           cfg: Any) -> int:  # fmt: skip
    local = wp.transform(wp.vec3(*pos), wp.quat(*xyzw(quat)))
    if body < 0:  # static: the shape at its world pose
        local = wp.transform_multiply(wp.transform(wp.vec3(*spec.pos), wp.quat(*xyzw(spec.quat))), local)
    kind = shape.kind
    label = spec.name
    if kind is ShapeKind.BOX:
        hx, hy, hz = (0.5 * s for s in shape.size)
        return int(builder.add_shape_box(body, xform=local, hx=hx, hy=hy, hz=hz, cfg=cfg, label=label))
    if kind is ShapeKind.SPHERE:
        return int(builder.add_shape_sphere(body, xform=local, radius=shape.radius, cfg=cfg, label=label))
    if kind is ShapeKind.CAPSULE:
        return int(builder.add_shape_capsule(body, xform=local, radius=shape.radius, half_height=0.5 * shape.length,
                                             cfg=cfg, label=label))  # fmt: skip
    if kind is ShapeKind.CYLINDER:
        return int(builder.add_shape_cylinder(body, xform=local, radius=shape.radius, half_height=0.5 * shape.length,
                                              cfg=cfg, label=label))  # fmt: skip
    if kind in (ShapeKind.CONVEX, ShapeKind.TRIMESH) and shape.mesh is not None:  # built, not declared (import)
        vertices = np.asarray(shape.mesh.vertices, dtype=np.float32)
        mesh = newton.Mesh(vertices, np.asarray(shape.mesh.faces, dtype=np.int32).ravel(), compute_inertia=False)
        add = builder.add_shape_convex_hull if kind is ShapeKind.CONVEX else builder.add_shape_mesh
        return int(add(body, xform=local, mesh=mesh, cfg=cfg, label=label))
    if kind is ShapeKind.PLANE:
        return int(builder.add_shape_plane(plane=None, xform=local, width=0.0, length=0.0, body=-1, cfg=cfg,
                                           label=label))  # fmt: skip
    raise UnsupportedFeature(f"Backend `newton` has no mapping for shape kind `{kind.value}` ({spec.name}).")


def _frame(wp: Any, spec: BodySpec | None, anchor: Any) -> Any:
    """The joint frame (at the anchor, the world's orientation) in ``spec``'s body frame (the world's: None)."""
    x_wj = wp.transform(wp.vec3(*anchor), wp.quat_identity())
    if spec is None:
        return x_wj
    x_wb = wp.transform(wp.vec3(*spec.pos), wp.quat(*xyzw(spec.quat)))
    return wp.transform_multiply(wp.transform_inverse(x_wb), x_wj)


def _anchor(spec: JointSpec, child: BodySpec) -> tuple[float, float, float]:
    """Where the joint's frames sit: the anchor; for a slider and a fixed joint (which have none in ODE) the
    child's centre of mass, so that XPBD's positional correction acts through it and does not turn the body
    (at the world's origin, 1.4 m from the lab's door, its first step ran backwards at -0.068 m/s)."""
    if spec.kind in (JointKind.SLIDER, JointKind.FIXED):
        r = quat_matrices(child.quat)
        return tuple(float(v) for v in np.asarray(child.pos) + r @ np.asarray(child.com))  # type: ignore[return-value]
    return spec.anchor


def _joints(wp: Any, newton: Any, builder: Any, world: CompiledWorld, groups: list[_tree.Group], body: list[int],
            options: NewtonOptions) -> list[JointHandle]:  # fmt: skip
    handles: dict[int, JointHandle] = {}
    specs = world.bodies
    for group in groups:
        ids = []
        if group.root is not None:  # a floating articulation: its root body's free joint first
            ids.append(builder.add_joint_free(body[group.root], parent=-1, label=f"free:{specs[group.root].name}"))
        for o in group.joints:
            spec = world.joints[o.joint]
            parent_spec = specs[o.parent] if o.parent is not None else None
            parent = body[o.parent] if o.parent is not None else -1
            anchor = _anchor(spec, specs[o.child])
            common = {
                "parent_xform": _frame(wp, parent_spec, anchor),
                "child_xform": _frame(wp, specs[o.child], anchor),
                "label": spec.name,
            }
            lo = -math.inf if spec.lo is None else spec.lo
            hi = math.inf if spec.hi is None else spec.hi
            if o.sign < 0:
                lo, hi = -hi, -lo
            limits = {
                "limit_lower": lo if math.isfinite(lo) else None,
                "limit_upper": hi if math.isfinite(hi) else None,
                "limit_ke": options.limit_stiffness,
                "limit_kd": options.limit_damping,
                "target_ke": 0.0,
                "target_kd": 0.0,
                "armature": 0.0,
                "friction": 0.0,
            }
            if spec.kind is JointKind.SLIDER:
                index = builder.add_joint_prismatic(parent, body[o.child], axis=wp.vec3(*spec.axis), **limits, **common)
            elif spec.kind is JointKind.HINGE:
                index = builder.add_joint_revolute(parent, body[o.child], axis=wp.vec3(*spec.axis), **limits, **common)
            elif spec.kind is JointKind.BALL:
                index = builder.add_joint_ball(parent, body[o.child], **common)
            elif spec.kind is JointKind.FIXED:
                index = builder.add_joint_fixed(parent, body[o.child], **common)
            else:
                raise UnsupportedFeature(
                    f"Backend `newton` does not map `{spec.kind.value}` joints (joint `{spec.name}`)."
                )
            ids.append(index)
            handles[o.joint] = JointHandle(spec, int(index), o.parent, o.child, o.sign, -1)
        builder.add_articulation(ids, label=f"articulation:{len(ids)}:{ids[0]}")
    return [handles[j] for j in range(len(world.joints))]


def _filters(world: CompiledWorld, builder: Any, shapes: list[list[int]]) -> None:
    """Exclude every shape pair of two bodies that cannot touch (static pairs never collide in Newton)."""
    touching = set(touching_pairs(world))
    n = len(world.bodies)
    for a in range(n):
        for b in range(a + 1, n):
            if (a, b) in touching or not shapes[a] or not shapes[b]:
                continue
            if world.bodies[a].motion is Motion.STATIC and world.bodies[b].motion is Motion.STATIC:
                continue
            for sa in shapes[a]:
                for sb in shapes[b]:
                    builder.add_shape_collision_filter_pair(sa, sb)
