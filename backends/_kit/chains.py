"""Several joints moving one body (MJCF), on engines whose joints each join two bodies: a chain of light bodies.

MuJoCo applies a body's joints in order: joint 1 moves the body's frame, joint 2 turns or slides about its
axis as joint 1 left it, and so on. An engine whose joint joins exactly two bodies (PyBullet, DART, ODE) gets
the same kinematics from a chain ``parent -[j1]- D1 -[j2]- D2 ... -[jn]- body``: each intermediate body
``Dk`` carries joint ``k + 1`` and is the body's frame after joints 1..k (at the start all of them coincide
with the body's frame, so each ``Dk`` is placed there, and every joint keeps its world axis and anchor).

Cost. An engine needs a mass on every moving body, so each ``Dk`` is a copy of the body scaled by
:data:`LIGHT` (mass ``LIGHT m``, inertia ``LIGHT I`` about the same centre of mass and axes), without shapes.
Its kinetic and potential energy are ``LIGHT`` times those of the body carried rigidly by the frame ``Dk``,
so the generalised mass matrix and gravity forces gain at most ``(n - 1) LIGHT`` times those of such copies:
for joints that meet at the body (every multi-joint body of dm_control's suite and pybullet_data: a hip's
x, y, z hinges at one point, a planar root's slides and hinge), a copy moves no more than the body does on
the same joint rates, and the accelerations change by a relative ``(n - 1) LIGHT`` at most: 2e-4 for the
largest chain (3 joints), far below what separates two engines' integrators. ``LIGHT`` is 1e-4, not smaller,
because ODE keeps its state in single precision and solves every joint's constraint row with the bodies'
inverse masses: a mass ratio of ``1/LIGHT`` loses ``log10(1/LIGHT)`` of its 7 digits. Measured on a two-hinge
pendulum against MuJoCo (which runs the file's joints natively), 1 s at h = 1 ms: at 1e-6 ODE gained 8 mJ in
10 ms (the energy watchdog stopped it); at 1e-4 ODE stays within 4.5e-5 rad, PyBullet and DART within 1.4e-6;
at 1e-2 all drift by 1.4e-4 rad (tests/backends/test_joint_chains.py checks the bound). ODE takes 1e-3
(``Backend.chain_light``): at 1e-4 its float32 LDLT factorisation meets a zero pivot on dm_control's
humanoid_CMU within 20 ms and on humanoid within 2 s ("d[i] != 0" in _dLDLTRemove, the process aborted), at
3e-4 humanoid_CMU blows up, at 1e-3 and 1e-2 both run 2 s with walker, cheetah and hopper; the bound grows
with it (a relative 2e-3 for a 3-joint chain), still below ODE's own float32 and ERP errors there.

The intermediate bodies come after the world's own (the runner never sees them: the base class reports the
world's bodies only); they have no shapes, so they are in no contact.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..types import BodySpec, CompiledWorld, JointKind, JointSpec, Motion, Shape, ShapeKind, Vec3

#: each intermediate body's mass and inertia as a fraction of the body's (module docstring: the cost); an
#: engine may ask for more (``Backend.chain_light``: ODE's float32 LCP, module docstring)
LIGHT = 1e-4


def _vec(a: np.ndarray) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


def _start_rates(world: CompiledWorld) -> dict[str, float]:
    """Each model joint's start rate (``ModelFile.start``); every other joint starts at rest."""
    return {name: rate for model in world.models for name, _, rate in model.start}


def _frame_velocity(
    parent: BodySpec | None, joints: list[JointSpec], rates: dict[str, float], at: np.ndarray
) -> tuple[Vec3, Vec3]:
    """The velocity of the point ``at`` and the angular velocity of the frame the parent carries through
    ``joints`` (in order), at the start: the parent's twist plus each joint's rate along its axis."""
    v = np.zeros(3) if parent is None else np.asarray(parent.lin_vel, float)
    w = np.zeros(3) if parent is None else np.asarray(parent.ang_vel, float)
    if parent is not None:
        v = v + np.cross(w, at - np.asarray(parent.pos, float))
    for joint in joints:
        rate, axis = rates.get(joint.name, 0.0), np.asarray(joint.axis, float)
        if joint.kind is JointKind.HINGE:
            w = w + rate * axis
            v = v + rate * np.cross(axis, at - np.asarray(joint.anchor, float))
        elif joint.kind is JointKind.SLIDER:
            v = v + rate * axis
    return _vec(v), _vec(w)


def light_copy(body: BodySpec, name: str, lin_vel: Vec3, ang_vel: Vec3, light: float = LIGHT) -> BodySpec:
    """The intermediate body: the body's frame, ``light`` of its mass and inertia, no shapes, no visuals."""
    return replace(
        body,
        name=name,
        motion=Motion.DYNAMIC,
        shape=Shape(ShapeKind.COMPOUND),
        shapes=(),
        visuals=(),
        mass=light * body.mass,
        inertia=(light * body.inertia[0], light * body.inertia[1], light * body.inertia[2]),
        lin_vel=lin_vel,
        ang_vel=ang_vel,
    )


def chained(world: CompiledWorld, light: float = LIGHT) -> CompiledWorld:
    """``world`` with every group of :attr:`CompiledWorld.joint_chains` made a chain through light bodies
    (``light`` of the body's mass and inertia), appended after the world's bodies; the joints keep their
    order and names (only their two bodies change)."""
    if not world.joint_chains:
        return world
    bodies = {b.name: b for b in world.bodies}
    index = {j.name: k for k, j in enumerate(world.joints)}
    joints = list(world.joints)
    extra: list[BodySpec] = []
    rates = _start_rates(world)
    taken = set(bodies)
    for names in world.joint_chains:
        chain = [world.joints[index[n]] for n in names]
        body = bodies[chain[0].body]
        parent = bodies.get(chain[0].other) if chain[0].other is not None else None
        at = np.asarray(body.pos, float)
        previous = chain[0].other
        for k, joint in enumerate(chain):
            if k == len(chain) - 1:
                joints[index[joint.name]] = replace(joint, other=previous)
                break
            name = f"{body.name} (after joint {joint.name})"
            while name in taken:
                name += "'"
            taken.add(name)
            lin, ang = _frame_velocity(parent, chain[: k + 1], rates, at)
            extra.append(light_copy(body, name, lin, ang, light))
            joints[index[joint.name]] = replace(joint, body=name, other=previous)
            previous = name
    return replace(world, bodies=world.bodies + tuple(extra), joints=tuple(joints), joint_chains=(),
                   chain_bodies=frozenset(b.name for b in extra))  # fmt: skip
