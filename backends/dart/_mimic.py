"""URDF `<mimic>` (``joint:mimic``) on DART 6.20's coupler constraint, with the offset that makes its row exact.

DART's ``CouplerConstraint`` (a follower joint with actuator ``MIMIC`` and ``setUseCouplerConstraint``) applies
the impulse pair of a coupling, +lambda on the follower and -m lambda on its leader, but its row is the
follower's rate alone: ``update`` asks for ``v_f' = (m q_l + c - q_f) / h`` (the leader's position at the start
of the step, error reduction 1) and ``getVelocityChange`` reports the follower's rate change only. So the
follower reaches where the leader *was*: after every step it is off by exactly ``-m h v_l'`` (measured on
tests/backends/test_mimic.py's pair: the ratio 1 to 4e-10, 6.2e-3 rad at the fastest), and the leader's rate
feeds back into the next step (two equal fingers swap rates each step).

The row ``v_f' - m v_l' = (m q_l + c - q_f) / h`` that a rigid coupling asks for is DART's own with the offset
``c + h u`` at ``u = m v_l'``. ``v_l'`` depends on ``u`` (the impulse moves the leader), affinely while the step's
set of active constraints stays, so :meth:`Mimics.step` solves for the ``u`` of every coupling that leaves each
coupling's rate residual at zero with the kit's Newton loop on trial engine steps from the saved state
(backends/_kit/coupling_solve.py: two trials and the kept step when affine), and keeps that step: the follower
then ends each step at ``m q_l' + c`` to rounding.
dartpy 6.20 allows no constraint written in Python (``ConstraintBase`` has no constructor, ``ConstraintInfo`` is
not bound).

Refused up front: two couplings in one joint tree (their rows share one LCP whose matrix, row = follower's rate,
impulse = the pair, is not symmetric: with DART's coupler alone, xarm6_with_gripper's five fingers on one leader
ended a step at 0.11 to 0.26 rad/s for 0.22 asked and threw the arm to 1e4 m/s in 6 ms; with the offsets solved
they held to rounding for 27 steps, then at 0.054 s, with 16 contact points in the step, no offsets made a
consistent step: the trials' slope matrix singular, cond 3e15), and a follower with a motor or friction loss (its
actuator is the coupling's).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import dartpy as dart
import numpy as np

from .._kit.coupling_solve import solve_coupled_step
from ..errors import UnsupportedFeature
from ..types import CompiledWorld
from . import _trees
from ._build import JointHandle

#: Newton steps on the leaders' rates at most per engine step (an affine step needs one)
ITERATIONS = 8
#: how far (rad or m) a kept step may leave a follower from its place, h x its rate residual: far under the
#: trace's rounding (1e-9), over the residual's own rounding (1.7e-13 rad/s x h at Franka Panda's fingers)
POSITION_TOLERANCE = 1e-12
#: singular values of the slope (rate residual per unit of offset rate, 1 when the leader is free) below this are
#: a locked coupling: double precision trials resolve far more (1e-13 rad/s)
RCOND = 1e-12


def check_mimics(world: CompiledWorld) -> None:
    """Refuse what the coupler cannot hold (module docstring): two couplings in one tree, a driven follower."""
    if not world.couplings:
        return
    index = {spec.name: k for k, spec in enumerate(world.joints)}
    tree_of: dict[int, int] = {}
    for number, tree in enumerate(_trees.plan(world)):
        tree_of.update({link.joint: number for link in tree.links})
        if tree.root_joint is not None:
            tree_of[tree.root_joint] = number
    seen: dict[int, str] = {}
    for coupling in world.couplings:
        spec = world.joints[index[coupling.joint]]
        if spec.motor is not None or spec.dynamics.frictionloss > 0.0:
            what = "a motor" if spec.motor is not None else "friction loss"
            raise UnsupportedFeature(
                f"Backend `dart` cannot run joint:mimic joint `{spec.name}` with {what}: DART's mimic joint "
                'takes the joint\'s actuator (docs/backends/dart.md, "Mimic joints")'
            )
        group = tree_of.get(index[coupling.joint], -1)
        if group in seen:
            raise UnsupportedFeature(
                f"Backend `dart` holds one joint:mimic per joint tree: `{seen[group]}` and `{coupling.joint}` share "
                "one; DART 6.20's coupler rows are not symmetric and its LCP solver leaves several unsolved "
                '(docs/backends/dart.md, "Mimic joints")'
            )
        seen[group] = coupling.joint


def _couple(follower: Any, leader: Any, ratio: float, offset: float) -> None:
    """Make ``follower`` DART's mimic of ``leader`` (follower = ratio x leader + offset) on a coupler."""
    if isinstance(follower, dart.dynamics.RevoluteJoint):
        props = follower.getRevoluteJointProperties()
    else:
        props = follower.getPrismaticJointProperties()
    props.mActuatorType = dart.dynamics.ActuatorType.MIMIC
    mimic = dart.dynamics.MimicDofProperties()
    mimic.mReferenceJoint, mimic.mReferenceDofIndex = leader, 0
    mimic.mMultiplier, mimic.mOffset = ratio, offset
    mimic.mConstraintType = dart.dynamics.MimicConstraintType.Coupler
    props.mMimicDofProps = [mimic]
    follower.setProperties(props)
    follower.setUseCouplerConstraint(True)


def _drop_redundant_stops(follower: Any, leader: Any, ratio: float, offset: float) -> None:
    """Stops of a follower whose range holds its leader's, mapped through the coupling, are never reached while the
    coupling holds, so they are not enforced: with them, a leader at its stop puts three rows on one coordinate
    pair in DART's LCP (the two stops and the coupler), which no offset then makes consistent (Franka Panda's
    fingers at 0.04 m, 0.688 s)."""
    if not (follower.areLimitsEnforced() and leader.areLimitsEnforced()):
        return
    lo, hi = sorted(
        (ratio * leader.getPositionLowerLimit(0) + offset, ratio * leader.getPositionUpperLimit(0) + offset)
    )
    slack = 1e-12 * max(1.0, abs(lo), abs(hi))
    if follower.getPositionLowerLimit(0) <= lo + slack and hi - slack <= follower.getPositionUpperLimit(0):
        follower.setLimitEnforcement(False)


class Mimics:
    """The world's couplings as DART couplers, stepped with the offset that makes each row exact."""

    def __init__(self, world: CompiledWorld, joints: list[JointHandle]) -> None:
        index = {handle.spec.name: handle for handle in joints}
        self._pairs: list[tuple[Any, Any, float, float]] = []
        for coupling in world.couplings:
            follower, leader = index[coupling.joint], index[coupling.leader]
            ratio, offset = coupling.engine_terms(follower.sign, leader.sign)
            _couple(follower.joint, leader.joint, ratio, offset)
            _drop_redundant_stops(follower.joint, leader.joint, ratio, offset)
            self._pairs.append((follower.joint, leader.joint, ratio, offset))

    def step(self, world: Any, issue: Callable[[], None], h: float) -> None:
        """One engine step (``issue`` sets the step's commands and forces, which World.step() clears)."""
        if not self._pairs:
            issue()
            world.step()
            return
        skeletons = [world.getSkeleton(i) for i in range(world.getNumSkeletons())]
        saved = [(s.getPositions(), s.getVelocities()) for s in skeletons]
        start = world.getTime()
        # each coupling's rate asked of the step: v_f' - m v_l' = (m q_l + c - q_f) / h, from the start
        asked = np.array([(m * lead.getPosition(0) + c - f.getPosition(0)) / h for f, lead, m, c in self._pairs])

        def restore() -> None:
            for skeleton, (q, v) in zip(skeletons, saved, strict=True):
                skeleton.setPositions(q)
                skeleton.setVelocities(v)
            world.setTime(start)

        def trial(u: np.ndarray) -> np.ndarray:
            """The couplings' rate residuals after a step from the start with each coupler's offset shifted by h u."""
            restore()
            for (follower, leader, ratio, offset), shift in zip(self._pairs, u, strict=True):
                _couple(follower, leader, ratio, offset + h * float(shift))
            issue()
            world.step()
            ends = [f.getVelocity(0) - m * lead.getVelocity(0) for f, lead, m, _ in self._pairs]
            return np.array(ends) - asked

        n = len(self._pairs)
        ones = np.ones(n)  # an offset rate of 1 moves the residual by 1 while the leader is free
        solved = solve_coupled_step(
            trial, np.zeros(n), lambda _: (ones, ones), np.full(n, POSITION_TOLERANCE), h, ITERATIONS, RCOND
        )
        if not solved.held:
            raise RuntimeError(f"DART's mimic coupling found no consistent step at t = {start:.6g} s")
