"""The scenario's shapes as MuJoCo geoms carrying their surfaces' contact parameters, and the explicit contact
pairs for the pairs of bodies with a surface of their own (the rows' design: the ``_model`` docstring).

The constraint impedance here is also the joints' stops' and couplings' (``_model``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from ..errors import UnsupportedFeature
from ..types import BodySpec, CompiledWorld, Motion, PlacedShape, Rgba, Shape, ShapeKind, Surface
from ._filters import excluded, touch
from ._options import MujocoOptions

#: Constant constraint impedance (solimp dmin = dmax): how nearly a contact or stop reaches its
#: reference acceleration. The rest, (1 - d) of the unconstrained acceleration, leaks through.
IMPEDANCE = 0.999
#: Friction coefficients are capped here (``inf`` included): with the elliptic cone this already
#: means no slip, and larger values only worsen the solver's conditioning.
MU_MAX = 1000.0

_GEOM = {
    ShapeKind.BOX: mujoco.mjtGeom.mjGEOM_BOX,
    ShapeKind.SPHERE: mujoco.mjtGeom.mjGEOM_SPHERE,
    ShapeKind.CAPSULE: mujoco.mjtGeom.mjGEOM_CAPSULE,
    ShapeKind.CYLINDER: mujoco.mjtGeom.mjGEOM_CYLINDER,
    ShapeKind.PLANE: mujoco.mjtGeom.mjGEOM_PLANE,
    ShapeKind.CONVEX: mujoco.mjtGeom.mjGEOM_MESH,
}
#: solimp of every contact, stop and coupling row: the constant impedance
SOLIMP = [IMPEDANCE, IMPEDANCE, 0.001, 0.5, 2.0]


@dataclass(frozen=True)
class ContactParams:
    """A surface as MuJoCo contact parameters at one engine step."""

    condim: int
    friction: tuple[float, float, float]  # slide, torsion, rolling (a pair repeats slide and rolling)
    solref: tuple[float, float]
    solreffriction: tuple[float, float]


def contact_solref(surface: Surface, h: float, opts: MujocoOptions) -> tuple[list[float], list[float]]:
    """(normal, friction) solref for a surface at engine step ``h`` (see the ``_model`` docstring)."""
    e = surface.bounce
    erp = opts.erp if e == 0.0 else opts.bounce_erp
    return [-erp / h**2, -(1.0 + e) / h], [-1.0, -1.0 / h]  # friction: the slip removed in one step


def _mu(surface: Surface) -> float:
    return min(surface.mu, MU_MAX)


def contact_params(surface: Surface, h: float, opts: MujocoOptions) -> ContactParams:
    solref, solreffriction = contact_solref(surface, h, opts)
    mu = _mu(surface)
    return ContactParams(3 if mu > 0.0 else 1, (mu, 0.005, 0.0001), (solref[0], solref[1]),
                         (solreffriction[0], solreffriction[1]))  # fmt: skip


def add_geoms(spec: Any, mj: Any, body: BodySpec, params: ContactParams, moving: bool) -> list[str]:
    """The body's geoms with the world's surface, named ``geom:<body>`` (a primitive body) or
    ``geom:<body>:<k>`` (the k-th shape of a compound body, at its pose in the body frame); only a geom of
    a moving rigid group has a contype, so two driven (static, kinematic) geoms never collide, as the
    contract says. Geoms carry no mass: the body's inertial is explicit."""
    if body.shape.kind is not ShapeKind.COMPOUND:
        name = f"geom:{body.name}"
        _add_geom(spec, mj, body, name, PlacedShape(body.shape), body.color, params, moving, local=False)
        return [name]
    names = [f"geom:{body.name}:{k}" for k in range(len(body.shapes))]
    for name, placed in zip(names, body.shapes, strict=True):
        color = placed.color if placed.color is not None else body.color
        _add_geom(spec, mj, body, name, placed, color, params, moving, local=True)
    return names


def _add_geom(
    spec: Any,
    mj: Any,
    body: BodySpec,
    name: str,
    placed: PlacedShape,
    color: Rgba,
    params: ContactParams,
    moving: bool,
    local: bool,
) -> None:
    shape = placed.shape
    if shape.kind is ShapeKind.PLANE and body.motion is not Motion.STATIC:
        raise UnsupportedFeature(f"mujoco: plane `{body.name}` must be static")
    if shape.kind not in _GEOM:
        raise UnsupportedFeature(f"mujoco: body `{body.name}` has a {shape.kind.value} shape, not supported")
    size = {
        ShapeKind.BOX: [s / 2.0 for s in shape.size],
        ShapeKind.SPHERE: [shape.radius, 0.0, 0.0],
        ShapeKind.CAPSULE: [shape.radius, shape.length / 2.0, 0.0],
        ShapeKind.CYLINDER: [shape.radius, shape.length / 2.0, 0.0],
        ShapeKind.PLANE: [0.0, 0.0, 1.0],  # infinite
        ShapeKind.CONVEX: [0.0, 0.0, 0.0],  # the mesh's
    }[shape.kind]
    pose = {"pos": list(placed.pos), "quat": list(placed.quat)} if local else {}
    geom = mj.add_geom(name=name, type=_GEOM[shape.kind], size=size, rgba=list(color), **pose)
    if shape.kind is ShapeKind.CONVEX:
        geom.meshname = _add_hull(spec, name, shape)
    geom.contype, geom.conaffinity = (1 if moving else 0), 1
    geom.condim, geom.friction = params.condim, list(params.friction)
    geom.solref, geom.solimp = list(params.solref), SOLIMP


def _add_hull(spec: Any, name: str, shape: Shape) -> str:
    """A mesh asset holding the hull's vertices and faces. MuJoCo collides with the convex hull of a mesh's
    vertices (qhull, ``maxhullvert`` -1: every vertex kept); every vertex of ``Shape.mesh`` is already a
    hull vertex, so that hull is exactly this one."""
    if shape.mesh is None:
        raise UnsupportedFeature(f"mujoco: convex shape `{name}` has no mesh")
    mesh = spec.add_mesh(name=f"mesh:{name}")
    mesh.uservert = np.asarray(shape.mesh.vertices, dtype=np.float64).ravel().tolist()
    mesh.userface = np.asarray(shape.mesh.faces, dtype=np.int32).ravel().tolist()
    mesh.maxhullvert = -1
    return str(mesh.name)


def add_pairs(
    spec: Any,
    world: CompiledWorld,
    group: dict[str, str],
    moving: set[str],
    geoms: dict[str, list[str]],
    default: ContactParams,
    h: float,
    opts: MujocoOptions,
) -> None:
    """An explicit contact pair for each pair of geoms whose bodies' own surface the geoms cannot give.

    A pair overrides MuJoCo's filtering and its own geom pair (MuJoCo merges the two), so it is made only
    where the bodies could touch: not both driven, not one rigid group, not joined or excluded.
    """
    skip = {frozenset(pair) for pair in excluded(world)}
    order = {b.name: i for i, b in enumerate(world.bodies)}
    seen: set[frozenset[str]] = set()
    for pair in world.pair_surfaces:  # the first one naming a pair is the pair's (CompiledWorld.surface)
        a, b = sorted((pair.a, pair.b), key=order.__getitem__)  # geom1 first in the world: its contact frame
        key = frozenset((a, b))
        if key in seen:
            continue
        seen.add(key)
        if a == b or key in skip or not touch(a, b, group, moving):
            continue
        params = contact_params(pair.surface, h, opts)
        if params == default:
            continue
        mu, spin, roll = params.friction
        for geom_a in geoms[a]:
            for geom_b in geoms[b]:
                spec.add_pair(
                    geomname1=geom_a,
                    geomname2=geom_b,
                    condim=params.condim,
                    friction=[mu, mu, spin, roll, roll],
                    solref=list(params.solref),
                    solreffriction=list(params.solreffriction),
                    solimp=SOLIMP,
                )
