"""Capsule against cylinder in panda3d's ODE: a prism stand-in for the cylinder, used against capsules only.

panda3d 1.10's ODE has no capsule-cylinder collider: ``dCollide`` returns 0 contacts for that pair even when
the shapes overlap, so they would pass through each other. ODE does collide a capsule with a triangle mesh,
so a cylinder that a capsule can touch gets a second geom on the same body at the same pose: a closed prism
of :data:`FACETS` side facets inscribed in it (its vertices on the cylinder's surface, its two end faces the
cylinder's). Category and collide bits make ODE test the prism against capsule geoms only (every other
shape meets the cylinder itself, and the cylinder still meets the capsule, giving no contact).

Error bound. The prism lies inside the cylinder: its end faces are the cylinder's, and its side is at most
the sagitta ``r (1 - cos(pi / FACETS))`` inside the curved surface (at a facet's middle; 0 at its edges). A
capsule touching the side therefore rests between 0 and ``r (1 - cos(pi / FACETS))`` closer to the axis than
on the true cylinder: 1.2e-3 r at 64 facets (0.12 mm for a 10 cm radius; 0.04 mm for the 3.4 cm hub
of dm_control's finger), plus ODE's usual contact softness.

A pair needs the prism only where the scene :func:`~backends.ode._build.build_scene` makes tests it: the two
shapes on two different bodies (ODE never tests two geoms of one body), at least one of them dynamic (the
bits of ``_build`` let static and kinematic geoms meet dynamic ones only), and not an excluded pair
(``CompiledWorld.excluded_pairs``: a joint's two links, MJCF contype/conaffinity and its parent filter,
`<exclude>`, the scenario's ``exclude_contacts``; the near-callback of ``_contacts`` skips them). So a model's
decoration cylinder on the same link as its capsule, or on the capsule's parent link, gets none.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from panda3d.core import BitMask32
from panda3d.ode import OdeTriMeshData, OdeTriMeshGeom

from ..types import BodySpec, CompiledWorld, Mesh, Motion, ShapeKind
from ._shapes import tri_mesh_data

#: side facets of a cylinder's stand-in prism (the error bound of the module docstring: 1.2e-3 r)
FACETS = 64
#: category bits of the prisms and of the capsules they meet, beside _build's motion bits 1, 2, 4
CAT_PRISM, CAT_CAPSULE_DYNAMIC, CAT_CAPSULE_STILL = 8, 16, 32


def prism_bodies(world: CompiledWorld) -> frozenset[int]:
    """The bodies whose cylinders need a prism: those a capsule on another body can touch."""
    excluded = frozenset(world.excluded_pairs) | {(b, a) for a, b in world.excluded_pairs}
    kinds = [{p.shape.kind for p in body.placed_shapes()} for body in world.bodies]
    capsules = [i for i, k in enumerate(kinds) if ShapeKind.CAPSULE in k]
    return frozenset(
        j
        for j, k in enumerate(kinds)
        if ShapeKind.CYLINDER in k and any(_can_touch(world, excluded, i, j) for i in capsules)
    )


def _can_touch(world: CompiledWorld, excluded: frozenset[tuple[str, str]], i: int, j: int) -> bool:
    """Whether the ODE scene tests bodies ``i`` and ``j`` against each other (module docstring)."""
    if i == j:
        return False
    a, b = world.bodies[i], world.bodies[j]
    if a.motion is not Motion.DYNAMIC and b.motion is not Motion.DYNAMIC:
        return False
    return (a.name, b.name) not in excluded


def prism(radius: float, length: float, facets: int = FACETS) -> Mesh:
    """A closed prism along z inscribed in the cylinder (radius, length), triangles wound counter-clockwise
    seen from outside (ODE's trimesh colliders take the winding as the outside)."""
    half = length / 2.0
    ring = [(radius * math.cos(2.0 * math.pi * k / facets), radius * math.sin(2.0 * math.pi * k / facets))
            for k in range(facets)]
    vertices = tuple((x, y, z) for z in (-half, half) for x, y in ring)  # bottom ring 0..n-1, top n..2n-1
    n = facets
    faces: list[tuple[int, int, int]] = []
    for k in range(n):
        a, b = k, (k + 1) % n
        faces += [(a, b, n + b), (a, n + b, n + a)]
    for k in range(1, n - 1):
        faces += [(0, k + 1, k), (n, n + k, n + k + 1)]  # bottom (seen from -z), top (seen from +z)
    return Mesh(vertices=vertices, faces=tuple(faces), source=f"cylinder-prism-{facets}")


class Prisms:
    """Adds the prisms of one scene's cylinders and marks its capsules (the bits that pair them)."""

    def __init__(self, world: CompiledWorld, meshes: dict[int, OdeTriMeshData]) -> None:
        self.bodies = prism_bodies(world)
        self._meshes = meshes  # the scene's mesh data (kept alive, destroyed with it)
        self._data: dict[tuple[float, float], OdeTriMeshData] = {}

    def add(self, space: Any, index: int, spec: BodySpec, body_geoms: Sequence[Any], body: Any | None) -> list[Any]:
        """Mark body ``index``'s capsule geoms; the prisms of its cylinder geoms (``body_geoms``, in
        ``spec.placed_shapes()`` order, their pose already set), to be added to the scene's geoms."""
        if not self.bodies:
            return []
        moving = spec.motion is Motion.DYNAMIC
        out: list[Any] = []
        for geom, placed in zip(body_geoms, spec.placed_shapes(), strict=True):
            kind = placed.shape.kind
            if kind is ShapeKind.CAPSULE:
                bit = CAT_CAPSULE_DYNAMIC if moving else CAT_CAPSULE_STILL
                geom.setCategoryBits(BitMask32(geom.getCategoryBits().getWord() | bit))
            elif kind is ShapeKind.CYLINDER and index in self.bodies:
                out.append(self._prism(space, geom, placed.shape.radius, placed.shape.length, body, moving))
        return out

    def _prism(self, space: Any, cylinder: Any, radius: float, length: float, body: Any | None, moving: bool) -> Any:
        key = (radius, length)
        data = self._data.get(key)
        if data is None:
            data = self._data[key] = tri_mesh_data(prism(radius, length))
            self._meshes[-len(self._data)] = data  # negative keys: never an id() of the scene's own meshes
        geom = OdeTriMeshGeom(space, data)
        if body is None:
            geom.setPosition(cylinder.getPosition())
            geom.setQuaternion(cylinder.getQuaternion())
        else:
            geom.setBody(body)
            if cylinder.isOffset():
                geom.setOffsetPosition(cylinder.getOffsetPosition())
                geom.setOffsetQuaternion(cylinder.getOffsetQuaternion())
        geom.setCategoryBits(BitMask32(CAT_PRISM))
        # a moving cylinder meets every capsule it can touch; a static or kinematic one the dynamic ones only
        geom.setCollideBits(BitMask32(CAT_CAPSULE_DYNAMIC | (CAT_CAPSULE_STILL if moving else 0)))
        return geom
