"""Armature at DART's constraint impulses: each step's impulse re-sized through the inertia with the armature.

DART's constraint solver (contacts, stops, couplers) computes its impulses and their velocity change with the
explicit articulated inertia, ``dv = M^-1 p`` (``p = J^T lambda``, the generalized impulse), which the armature
emulation (_armature: DART's implicit damping term) does not reach: an impact spreads velocity over the joints as
if they had none, and a joint whose armature outweighs its link (dm_control's dog: 1e-4 kg m^2 on tail links of
1e-9) leaves the impact with its rotor's energy multiplied. The energy watchdog stopped six MJCF models so.
dartpy 6.20 offers no way into the solver: GenericJoint has no armature, ``ConstraintBase`` has no Python
constructor, the servo's CFM is one static relative value.

So after each engine step in which a skeleton with armature took constraint impulses, the adapter keeps DART's
impulse direction ``p`` (``M dv``, from the skeleton's velocity change ``Skeleton.getVelocityChanges`` and its
mass matrix at the step's start, where the solver took it) and solves its size with the armature: the step's
velocity change becomes ``s (M + A)^-1 p``, ``s = p.dv / p.(M + A)^-1 p``, which keeps the impulse's power
``p.v'`` as DART's LCP set it. For one constraint row (one frictionless contact normal, one stop) that is the
exact step with the armature in the solver: the row's velocity ends where DART's LCP put it (its target does not
depend on the inertia), with the impulse that ``M + A`` needs for it. With several rows their ratios stay those
DART solved with ``M`` (an approximation, measured in docs/backends/dart.md). It adds no kinetic energy (metric
``M + A``) beyond DART's own targets: with ``v*`` the rate before the impulse, ``p.v* = p.v' - p.dv``, so the
energy changes by ``s (p.v' - p.dv / 2)``, where ``p.v'`` is the work of the targets (restitution, position
correction; 0 for a plastic contact that holds, < 0 for friction). Skeletons that touch one another in the step
share one ``s`` (their impulses are each other's reactions: momentum is kept). Positions are integrated again from
the step's start with the new rates (``Skeleton.integratePositions``, as ``World.step`` does).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from .._kit.components import components
from ..types import JointKind


class ArmatureImpacts:
    """Re-sizes each engine step's constraint impulses with the joints' armature (module docstring)."""

    def __init__(self, skeletons: Iterable[Any], joints: Sequence[Any]) -> None:
        """``skeletons``: the world's mobile skeletons; ``joints``: the built JointHandles."""
        self._skeletons = {s.getName(): s for s in skeletons if s.getNumDofs() > 0}
        #: the coordinates the solver moves (a kinematic root's, commanded, keeps its rate)
        self._dynamic = {n: _dynamic_dofs(s) for n, s in self._skeletons.items()}
        armature: dict[str, np.ndarray] = {}
        for handle in joints:
            a = handle.spec.dynamics.armature
            if a <= 0.0 or handle.spec.kind not in (JointKind.HINGE, JointKind.SLIDER):
                continue
            skeleton = handle.joint.getSkeleton()
            column = armature.setdefault(skeleton.getName(), np.zeros(skeleton.getNumDofs()))
            column[handle.joint.getIndexInSkeleton(0)] += a
        self._armature = armature
        self._start: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def before(self) -> None:
        """At the start of an engine step: each mobile skeleton's positions and mass matrix."""
        if self._armature:
            self._start = {n: (s.getPositions(), s.getMassMatrix()) for n, s in self._skeletons.items()}

    def after(self, h: float, touching: Callable[[], Iterable[tuple[str, str]]]) -> None:
        """After the engine step: re-size the impulses of each group of touching skeletons that holds armature.
        ``touching`` gives the pairs of skeletons (by name) in contact in the step; called only when needed."""
        if not self._armature:
            return
        # DART clears the constraint impulses at each solve: a skeleton without any kept a stale velocity change
        hit = {n for n, s in self._skeletons.items() if np.any(s.getConstraintForces())}
        if not hit & self._armature.keys():
            return
        for group in _groups(hit, touching() if len(hit) > 1 else ()):
            if group & self._armature.keys():
                self._resize(sorted(group), h)

    def _resize(self, names: list[str], h: float) -> None:
        parts = []
        power = inert = 0.0
        for name in names:
            skeleton = self._skeletons[name]
            start, mass = self._start[name]
            dv = np.asarray(skeleton.getVelocityChanges(), dtype=float)
            free = self._dynamic[name]
            impulse = mass @ dv
            armature = self._armature.get(name, np.zeros(len(dv)))
            moved = np.zeros(len(dv))
            moved[free] = np.linalg.solve(mass[np.ix_(free, free)] + np.diag(armature[free]), impulse[free])
            power += float(impulse @ dv)
            inert += float(impulse @ moved)
            parts.append((skeleton, start, dv, moved))
        if inert <= 0.0:
            return
        scale = power / inert
        for skeleton, start, dv, moved in parts:
            velocities = skeleton.getVelocities() - dv + scale * moved
            skeleton.setPositions(start)
            skeleton.setVelocities(velocities)
            skeleton.integratePositions(h)


def _dynamic_dofs(skeleton: Any) -> np.ndarray:
    """The indices of the skeleton's coordinates that are not kinematic (VELOCITY, LOCKED, ACCELERATION)."""
    out = []
    for j in range(skeleton.getNumJoints()):
        joint = skeleton.getJoint(j)
        if not joint.isKinematic():
            out += [joint.getIndexInSkeleton(k) for k in range(joint.getNumDofs())]
    return np.array(sorted(out), dtype=np.intp)


def _groups(hit: set[str], pairs: Iterable[tuple[str, str]]) -> list[set[str]]:
    """The skeletons in ``hit`` joined by touching ``pairs`` (connected components)."""
    out: dict[str, set[str]] = {}
    for name, root in components(hit, pairs).items():
        out.setdefault(root, set()).add(name)
    return list(out.values())
