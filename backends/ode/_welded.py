"""Bodies welded to a moving parent: inertia lent by the parent where float32 cannot resolve the body's own.

A body whose only joint moving it is a fixed joint to a dynamic parent (MJCF's jointless body, a URDF link with
mass on a fixed joint) turns with its parent: the two are one rigid body, whose motion depends on their
composite mass, centre of mass and inertia only, not on how the inertia is split between them (the split shows
only in the weld's own reaction). ODE still steps them as two bodies held by the fixed joint's six rows, built in
single precision with each body's inverse inertia: dm_control's manipulator and stacker weld a "pinch site" of
1e-6 kg and 1e-12 kg m^2 to the hand, 2.1e-9 of the model's largest principal inertia, below what float32
resolves beside it (2^-23; ``_ranges``).

Where such a body's smallest principal inertia is below FLOAT32_EPS of the world's largest, the parent lends it
``d`` times the identity: the body gets ``I_b + d 1`` and the parent ``I_p - d 1`` (each about its own centre of
mass). The composite's inertia about any point is unchanged exactly (the identity is the same in every frame
and the parallel-axis terms depend only on the masses and centres, which stay), so the welded pair moves as
before. ``d`` brings the body's smallest moment to sqrt(FLOAT32_EPS) of the largest (half of float32's bits
between them), and is lent only where the parent keeps a valid tensor with room to spare: ``d`` at most half
its smallest principal moment and half its triangle slack A + B - C. Otherwise nothing is lent and the range
check refuses the world as before.
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..types import BodySpec, CompiledWorld, JointKind, Motion
from ._held import FLOAT32_EPS


def welded_bodies(world: CompiledWorld) -> dict[str, str]:
    """Each dynamic body whose only joint moving it (``JointSpec.body``) is a fixed joint to a dynamic parent:
    that parent's name."""
    motion = {b.name: b.motion for b in world.bodies}
    moving: dict[str, list[tuple[JointKind, str | None]]] = {}
    for j in world.joints:
        moving.setdefault(j.body, []).append((j.kind, j.other))
    out = {}
    for name, joints in moving.items():
        if len(joints) != 1 or motion.get(name) is not Motion.DYNAMIC:
            continue
        kind, other = joints[0]
        if kind is JointKind.FIXED and other is not None and motion.get(other) is Motion.DYNAMIC:
            out[name] = other
    return out


def lend_welded_inertia(world: CompiledWorld) -> CompiledWorld:
    """``world`` with inertia lent to each welded body float32 cannot resolve, where its parent can spare it
    (module docstring)."""
    welded = welded_bodies(world)
    dynamic = [b for b in world.bodies if b.motion is Motion.DYNAMIC]
    if not welded or not dynamic:
        return world
    largest = max(max(b.inertia) for b in dynamic)
    target = math.sqrt(FLOAT32_EPS) * largest
    by_name: dict[str, BodySpec] = {b.name: b for b in world.bodies}
    lent = False
    for name in sorted(welded):  # sorted: the same world whatever the joints' order
        body = by_name[name]
        if min(body.inertia) >= FLOAT32_EPS * largest:
            continue
        parent = by_name[welded[name]]
        a, b, c = sorted(parent.inertia)
        d = target - min(body.inertia)
        if d > 0.5 * a or d > 0.5 * (a + b - c):
            continue
        by_name[name] = replace(body, inertia=(body.inertia[0] + d, body.inertia[1] + d, body.inertia[2] + d))
        p = parent.inertia
        by_name[parent.name] = replace(parent, inertia=(p[0] - d, p[1] - d, p[2] - d))
        lent = True
    if not lent:
        return world
    return replace(world, bodies=tuple(by_name[b.name] for b in world.bodies))
