"""Bodies whose orientation ODE's joints hold to the world: their rotational inertia raised where float32 needs it.

A body joined to the world (or a static body) only through sliders and fixed joints, directly or through
other such bodies, never turns: its angular velocity stays the world's, 0, and its inertia tensor enters no
equation of its motion (the joints' angular rows take whatever torque holds it). ODE still builds those rows
with the body's inverse inertia, in single precision: pybullet_data's pusher has a target of 4.0e-10 kg with
principal inertia 6.4e-13 kg m^2 on two sliders (the light body between them, backends/_kit/chains.py,
1e-3 of that: 6.4e-16 kg m^2), so its angular rows weigh 1/I = 1.6e15 against 1/m = 2.5e12 for its linear
ones, and ODE's first dWorldStep gave it a quaternion it could not normalise (the process aborted:
"bNormalizationResult" in _dNormalize4). Where a held body's smallest principal inertia is below 2^-23
(float32's epsilon) of the largest of the world's dynamic bodies (pusher's target: 1.8e-12 of the arm's
0.36 kg m^2), the backend takes each of its principal inertias as at least ``m * (1 m)^2`` (:data:`HELD_RADIUS`),
so its angular rows weigh no more than its linear ones per unit of ODE's (SI) coordinates: exact for the
motion (the body does not turn), and pusher runs. Other held bodies keep their inertia: raised, the lab's
400 kg door on its slider changed ODE's rounding (its LCP failures at CFM 1e-10 became an abort), and
pybullet_data's ant (its torso welded to the world by the file) went from the energy watchdog to running: the
raise stays where float32 cannot do without it.
"""

from __future__ import annotations

from dataclasses import replace

from ..types import CompiledWorld, JointKind, Motion

#: float32's epsilon: the smallest relative difference single-precision ODE resolves
FLOAT32_EPS = 2.0**-23
#: the radius of gyration (m) a held body's inertia is raised to at least: I >= m * HELD_RADIUS^2
HELD_RADIUS = 1.0
_HOLDING = (JointKind.SLIDER, JointKind.FIXED)


def held_bodies(world: CompiledWorld) -> frozenset[str]:
    """The dynamic bodies that every joint moving them (``JointSpec.body``) joins by a slider or a fixed joint
    to the world, a static body or another such body; a body with no joint moving it is free, not held."""
    motion = {b.name: b.motion for b in world.bodies}
    moving: dict[str, list[tuple[JointKind, str | None]]] = {}
    for j in world.joints:
        moving.setdefault(j.body, []).append((j.kind, j.other))
    held: set[str] = set()
    changed = True
    while changed:  # grow from the world outwards: a body is held once all its joints' others are
        changed = False
        for name, joints in moving.items():
            if name in held or motion.get(name) is not Motion.DYNAMIC:
                continue
            if all(kind in _HOLDING and (other is None or motion.get(other) is Motion.STATIC or other in held)
                   for kind, other in joints):
                held.add(name)
                changed = True
    return frozenset(held)


def raise_held_inertia(world: CompiledWorld) -> CompiledWorld:
    """``world`` with each held body whose smallest principal inertia is below FLOAT32_EPS of the largest
    dynamic body's given principal inertias of at least ``m * HELD_RADIUS^2`` (module docstring)."""
    held = held_bodies(world)
    if not held:
        return world
    largest = max(max(b.inertia) for b in world.bodies if b.motion is Motion.DYNAMIC)
    bodies = []
    for b in world.bodies:
        floor = b.mass * HELD_RADIUS**2
        if b.name in held and min(b.inertia) < FLOAT32_EPS * largest and min(b.inertia) < floor:
            b = replace(b, inertia=(max(b.inertia[0], floor), max(b.inertia[1], floor), max(b.inertia[2], floor)))
        bodies.append(b)
    return replace(world, bodies=tuple(bodies))
