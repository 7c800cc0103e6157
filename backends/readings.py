"""What a backend reports back: the states of bodies and joints, the contacts after a step, and the model as
the engine built it (re-exported by :mod:`backends.types`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple

import numpy as np

from .basic_types import JointKind, Vec3


@dataclass(frozen=True)
class ImportedBody:
    """A body as the engine holds it once built (:meth:`backends.base.Backend.imported_model`), read back from
    the engine: what it will simulate, whatever the world asked for."""

    name: str  # the CompiledWorld body's name
    mass: float  # kg
    inertia: Vec3  # principal moments about the COM (kg m^2), ascending (the axes are not compared)
    com: Vec3  # the centre of mass in the body frame (m)
    shapes: int  # collision shapes the engine built for the body


@dataclass(frozen=True)
class ImportedJoint:
    """A joint as the engine holds it once built, in the world joint's coordinate (counted from the start, its
    sign), read back from the engine. ``None``: the engine holds no such value (no stop on that side, no own
    damping or friction parameter, no limit it enforces by itself); what the runner realises instead (its
    motor's damping and friction loss, its caps on effort and velocity) is not the engine's and is not here."""

    name: str  # the CompiledWorld joint's name
    kind: JointKind  # the engine's joint type, mapped to ours
    axis: Vec3 | None  # world frame, unit, at the start (slider, hinge; universal: first axis); None: no axis
    lo: float | None  # stops: metres or radians from the start
    hi: float | None
    damping: float | None  # the engine's own joint damping (N m s/rad or N s/m)
    frictionloss: float | None  # the engine's own dry joint friction (N m or N)
    effort: float | None  # a force limit the engine enforces by itself (N m or N)
    velocity: float | None  # a rate limit the engine enforces by itself (rad/s or m/s)


@dataclass(frozen=True)
class ImportedModel:
    """What an engine built, read back before any step: every dynamic body and every joint, in
    ``CompiledWorld`` order (static bodies carry no mass in any engine and are left out)."""

    backend: str
    bodies: tuple[ImportedBody, ...]
    joints: tuple[ImportedJoint, ...]
    #: where a value is the adapter's rather than the engine's (e.g. ODE keeps the COM at the body's origin,
    #: so the COM offset is the adapter's frame), one line each
    notes: tuple[str, ...] = ()


@dataclass
class BodyStates:
    """States of every body in ``CompiledWorld.bodies`` order, world frame."""

    pos: np.ndarray  # (N, 3)
    quat: np.ndarray  # (N, 4), w x y z
    lin_vel: np.ndarray  # (N, 3)
    ang_vel: np.ndarray  # (N, 3)

    @classmethod
    def from_rows(cls, rows: np.ndarray) -> BodyStates:
        """Views of an (N, 13) array whose rows are pos, quat (w x y z), lin_vel, ang_vel."""
        return cls(rows[:, 0:3], rows[:, 3:7], rows[:, 7:10], rows[:, 10:13])

    def rows(self) -> np.ndarray:
        """One (N, 13) float64 array: each row pos, quat (w x y z), lin_vel, ang_vel."""
        return np.concatenate((self.pos, self.quat, self.lin_vel, self.ang_vel), axis=1).astype(np.float64, copy=False)


@dataclass
class JointStates:
    """States of every joint in ``CompiledWorld.joints`` order (NaN where a value does not exist)."""

    position: np.ndarray  # (M,) slider m / hinge rad; NaN for ball and fixed
    velocity: np.ndarray  # (M,)
    motor_force: np.ndarray  # (M,) force or torque the motor applied in the last step; 0 if none


class Contact(NamedTuple):
    """Touching bodies after the last step (indices into ``CompiledWorld.bodies``, ``a < b``).

    A named tuple rather than a frozen dataclass: adapters make one per touching pair per step, and a
    named tuple is built about 2.5 times faster (0.5 us against 1.2 us).
    """

    a: int
    b: int
    points: int  # number of contact points with distance <= 0
    depth: float  # largest penetration depth, >= 0
    normal_force: float  # summed normal force in N; NaN if the engine cannot say


class ContactPoint(NamedTuple):
    """One contact point of a touching pair (``a < b``, indices into ``CompiledWorld.bodies``) in the last
    engine step of the last scenario step (``Backend.contact_points()``; docs/semantics.md, "Contact points").
    """

    a: int
    b: int
    pos: Vec3  # world frame, m: where the engine places the point (between the two surfaces)
    normal: Vec3  # unit, world frame, pointing from body a to body b: a pushes b along +normal
    depth: float  # penetration, m (>= 0 when touching)
    force: float  # normal force, N, >= 0: the impulse along the normal in that engine step / its length


#: ``Contact`` from a (a, b, points, depth, normal_force) tuple without ``NamedTuple.__new__``'s Python
#: frame (``Contact._make`` minus its length check): for adapters that build one per pair per step.
#: The fields must already be plain ``int`` and ``float``.
new_contact: Callable[[tuple[int, int, int, float, float]], Contact] = partial(tuple.__new__, Contact)
