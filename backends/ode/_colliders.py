"""Shape pairs panda3d's ODE cannot collide, refused before the run when two such shapes can touch.

panda3d 1.10's ODE has no capsule-cylinder collider: ``dCollide`` returns 0 contacts for that pair even
when the shapes overlap, so they would pass through each other. A scenario is refused only when such a pair
can actually be tested by the scene :func:`~backends.ode._build.build_scene` makes, that is when its two
shapes are

* on two different bodies (ODE never tests two geoms of one body, and a static body's geoms are static),
* of which at least one is dynamic (the category/collide bits of ``_build`` let static and kinematic geoms
  meet dynamic ones only),
* that are not an excluded pair (``CompiledWorld.excluded_pairs``: a joint's two links, MJCF
  contype/conaffinity and its parent filter, `<exclude>`, the scenario's ``exclude_contacts``; the
  near-callback of ``_contacts`` skips them).

So a model's decoration cylinder on the same link as its capsule, or a cylinder on a link's parent, runs;
a free capsule that can fall on a cylinder is refused, naming both bodies.
"""

from __future__ import annotations

from ..errors import UnsupportedFeature
from ..types import CompiledWorld, Motion, ShapeKind

#: shape kinds panda3d's ODE has no collider for (0 contacts whatever the overlap)
MISSING_COLLIDERS = ((ShapeKind.CAPSULE, ShapeKind.CYLINDER),)


def can_touch(world: CompiledWorld, excluded: frozenset[tuple[str, str]], i: int, j: int) -> bool:
    """Whether the ODE scene tests bodies ``i`` and ``j`` against each other (module docstring)."""
    if i == j:
        return False
    a, b = world.bodies[i], world.bodies[j]
    if a.motion is not Motion.DYNAMIC and b.motion is not Motion.DYNAMIC:
        return False
    return (a.name, b.name) not in excluded


def check_colliders(world: CompiledWorld) -> None:
    """Refuse the first body pair (in body order) holding two shapes ODE cannot collide that can touch."""
    excluded = frozenset(world.excluded_pairs) | {(b, a) for a, b in world.excluded_pairs}
    kinds = [{p.shape.kind for p in body.placed_shapes()} for body in world.bodies]
    for first, second in MISSING_COLLIDERS:
        holders = [i for i, k in enumerate(kinds) if first in k]
        others = [j for j, k in enumerate(kinds) if second in k]
        for i in holders:
            for j in others:
                if can_touch(world, excluded, i, j):
                    a, b = world.bodies[i].name, world.bodies[j].name
                    raise UnsupportedFeature(
                        f"Body `{a}` (a {first.value}) and body `{b}` (a {second.value}) can touch, and ODE "
                        f"(panda3d) has no {first.value}-{second.value} collider: they would pass through each "
                        "other. Exclude the pair (`exclude_contacts`) or run another backend."
                    )
