"""When the DART adapter's ``bounce_vel`` pass need not read its contacts: no contact can bounce in the engine step.

The pass (``_backend._match_touching_pairs``) collides the world before DART's step, reads every contact
point and sets bounce 0 for the pairs approaching below their ``bounce_vel``: on the bench's 100-box pile
1.8 ms of a 3.1 ms step, where DART's own step takes 1.2 ms; the collision query is 0.2-0.45 ms of it, the
rest is Python reading the points (five dartpy calls per point) and the bodies' motion.

DART uses the restitution coefficient in one place only (``ContactConstraint::getInformation``, 6.20): a
contact point bounces when ``e * v > 0.1 m/s`` (``DART_BOUNCING_VELOCITY_THRESHOLD``), ``v`` its approach
speed along the normal after the step's unconstrained velocity update. In a step where no point of any
two bodies can approach faster than ``0.1 / e_max`` (``e_max`` the world's largest bounce), the shapes'
restitution values change nothing. What the pass sets depends only on that step's touching and plastic
pairs, never on earlier steps, so such a step may instead take the build's values (which give every pair its
friction) without reading a contact, and the next step that reads them sets what it would have set anyway.
The query itself still runs in every step: DART's ODE detector keeps a contact history per pair that every
query updates and that fills in later queries' contacts (a pair with fewer than three points), DART's own
included (``_backend``). The physics stays bit for bit (``tests/backends/test_dart_gate.py``; the traces of
every scenario compared with ``cmp``).

The bound used here, for a world of free bodies (each a FreeJoint skeleton of its own, the centre of mass
at the body origin) and static ones, in an engine step without one-step forces: a point of body ``i`` at
most ``r_i`` from its origin moves at most ``|v| + (|w| + h k |w|^2) r_i + h |w| |v|`` after the update
besides gravity's ``g h`` (``k`` the ratio of its largest to smallest moment of inertia, for the gyroscopic
term), with ``r_i`` twice the shape's bounding radius (a contact point may lie outside a shape by the
penetration); two bodies approach at most at the sum of their bounds plus ``|g| h`` (gravity moves two free
bodies alike, a static one not at all), and the largest such sum is that of the two fastest bodies. The
gate asks it to stay 20 % below ``0.1 / e_max``; worlds with joints, kinematic bodies, centre-of-mass
offsets or pair surfaces that need solving per step always read. This module does not import the engine.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..types import BodySpec, CompiledWorld, Motion, Shape, ShapeKind

#: DART's ``DART_BOUNCING_VELOCITY_THRESHOLD`` (m/s): a point bounces only when e times its speed exceeds it.
DART_BOUNCE_THRESHOLD = 0.1
#: The share of ``0.1 / e_max`` the bound may reach for the pass to be left out.
SAFETY = 0.8


def shape_radius(shape: Shape) -> float:
    """The largest distance from the shape's origin to a point of it (inf for a plane)."""
    if shape.kind is ShapeKind.BOX:
        return 0.5 * math.sqrt(sum(x * x for x in shape.size))
    if shape.kind is ShapeKind.SPHERE:
        return shape.radius
    if shape.kind is ShapeKind.CAPSULE:
        return shape.radius + 0.5 * shape.length
    if shape.kind is ShapeKind.CYLINDER:
        return math.hypot(shape.radius, 0.5 * shape.length)
    if shape.kind in (ShapeKind.CONVEX, ShapeKind.TRIMESH) and shape.mesh is not None:
        return max((math.sqrt(sum(c * c for c in v)) for v in shape.mesh.vertices), default=0.0)
    return math.inf


def body_radius(body: BodySpec) -> float:
    """The largest distance from the body's origin to a point of its shapes."""
    parts = body.placed_shapes()
    return max((math.sqrt(sum(c * c for c in p.pos)) + shape_radius(p.shape) for p in parts), default=0.0)


class BounceGate:
    """``quiet(velocities, h)``: whether no contact of the coming engine step can bounce.

    ``free`` are the indices of the free bodies, in the order of the velocity rows the adapter reads
    ([angular, linear] per body, world frame). :attr:`usable` is False for a world the bound does not
    cover (the pass then runs every step).
    """

    def __init__(self, world: CompiledWorld, free: Sequence[int], usable: bool) -> None:
        bodies = world.bodies
        free_set = set(free)
        covered = all(
            b.motion is Motion.STATIC or (i in free_set and b.motion is Motion.DYNAMIC and b.com == (0.0, 0.0, 0.0))
            for i, b in enumerate(bodies)
        )
        e_max = max([world.default_surface.bounce, *(p.surface.bounce for p in world.pair_surfaces)])
        self.usable = usable and covered and not world.joints and e_max > 0.0
        self._limit = SAFETY * DART_BOUNCE_THRESHOLD / e_max if e_max > 0.0 else math.inf
        self._g = float(np.linalg.norm(world.gravity))
        self._reach = np.array([2.0 * body_radius(bodies[i]) for i in free], dtype=float)
        moments = [bodies[i].inertia for i in free]
        self._k = np.array([max(m) / min(m) if min(m) > 0.0 else math.inf for m in moments], dtype=float)
        self.usable = self.usable and bool(np.isfinite(self._reach).all() and np.isfinite(self._k).all())

    def quiet(self, velocities: np.ndarray, h: float) -> bool:
        """Whether the fastest two free bodies (``velocities``: (N, 6) rows [angular, linear]) together stay
        below the speed at which a contact could bounce."""
        if len(velocities) == 0:
            return True
        w = np.sqrt(np.einsum("ij,ij->i", velocities[:, :3], velocities[:, :3]))
        v = np.sqrt(np.einsum("ij,ij->i", velocities[:, 3:], velocities[:, 3:]))
        bound = v + (w + h * self._k * w * w) * self._reach + h * w * v
        fastest = bound[0] if len(bound) == 1 else np.partition(bound, len(bound) - 2)[-2:].sum()
        return bool(fastest + self._g * h < self._limit)
