"""URDF `<mimic>` / a two-joint MJCF equality (``joint:mimic``) on ODE: a force pair solved for every step.

ODE's joints join two bodies, and a coupling ``q_f = m q_l + c`` spans up to four (the follower's two and the
leader's two), so it cannot be one ODE joint, and ODE has no gear joint. It is held instead by the generalised
force pair a rigid coupling's row ``J = [e_f, -m e_l]`` puts on the bodies, ``J^T u``: +u on the follower's
coordinate and -m u on the leader's (``dJointAddHingeTorque`` / ``dJointAddSliderForce``, whose J^T f is the
joint's motor-row Jacobian: ``_joint_dynamics.motor_row_rate`` is its J v). ``u`` is chosen so that after the
step the coupling's rate residual ``v_f' - m v_l' - (m q_l + c - q_f) / h`` is zero (error reduction 1 from
the start-of-step positions): that is exactly the constraint force of a rigid coupling, two-way (the leader
feels the reaction), with no asymmetric row in ODE's LCP. The step is affine in ``u`` while its active set
stays, so the kit's Newton loop (backends/_kit/coupling_solve.py) finds it on trial steps from the saved
state; it starts from the last step's ``u`` and slope (a coupling's force and effective inertia change little
from one step to the next), so a step usually takes two ``dWorldStep``.

A trial leaves nothing behind: every body's position, quaternion and velocities are put back before each
trial, the first too (``dBodySetQuaternion`` renormalises: a quaternion read and set back changes in its last
bit one time in four, so every trial starts from the same re-set state), and ODE's random seed (quickstep
reorders its rows with ``dRandInt``). The step's contact joints, made once by the step's collide from the
start positions, serve every trial (the group is emptied after the kept step, as without couplings); armature
targets are set once and the springs' forces, computed once, are added again for each trial, as the body
forces are (ODE clears its accumulators after each ``dWorldStep``).

Tolerance (float32, ``dSINGLE``): a kept step leaves each follower within the float32 resolution of the
coordinates the coupling compares, ``r_f + |m| r_l``. A hinge's angle is twice the half-angle of the relative
quaternion ``q1* q2``, whose components ODE sums from four float32 products of unit quaternions (about 2 eps32
each, eps32 = 2^-23): it resolves to :data:`HINGE_RESOLUTION` eps32 x max(1 rad, |q|). A slider's position is
the axis times the difference of its bodies' world positions, three components rounded at eps32 |p| summed:
:data:`SLIDER_RESOLUTION` eps32 x the larger |p| (m). Closer than that no coordinate can be read or set. A
trial's rates are float32 too (``eps32 |v|``), which the step's h makes far smaller than that bound.

A step in which ODE reports that its LCP solver failed ("LCP internal error") is not iterated on: its rates
are no affine function of the force, and each further ``dWorldStep`` on that edge risks ODE's abort on a zero
pivot (xarm6_with_gripper aborted so in a slope's trial); the trial taken is kept and the log says so once per
coupling. A coupling that contacts or stops lock (the slope singular) keeps the least-squares step on the rest; one
not held to tolerance after :data:`ITERATIONS` Newton steps keeps the trial with the smallest residual, and
the run's log says so once per coupling (``messages``), with the residual.

Refused up front: two couplings in one group of jointed bodies. Their force pairs meet in the same bodies, and
the trial steps' rates stop being an affine function of the forces where the group's stops and couplings
switch: pybullet_data's xarm6_with_gripper (five fingers mimicking one joint, every joint starting at its
lower stop 0), held 1 m above the ground with a fixed base, warned "not held" with one coupling (0.28 mm at
0.162 s), ran with two, and aborted the process with three ("bNormalizationResult" in _dNormalize4, signal 6)
and with all five (a zero pivot in _dLDLTRemove); no trial schedule found was safe, so the run is refused, as
on DART (backends/dart/_mimic.py), rather than let ODE abort.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from panda3d.core import Quat
from panda3d.ode import OdeBody, OdeUtil

from .._kit.coupling_solve import solve_coupled_step
from ..errors import UnsupportedFeature
from ..types import CompiledWorld, JointKind, Motion
from . import _native
from ._build import JointHandle, Scene
from ._joint_dynamics import motor_row_rate
from ._ranges import jointed_groups

#: Newton steps at most per engine step (an affine step needs one)
ITERATIONS = 8
#: float32's epsilon
EPS32 = 2.0**-23
#: a hinge angle's and a slider position's float32 resolution in eps32 of their magnitude (module docstring)
HINGE_RESOLUTION, SLIDER_RESOLUTION = 4.0, 3.0
#: a slope's nudge changes its coupling's rate by sqrt(eps32) of the rates' scale: two float32 trials then
#: measure the slope to sqrt(eps32)
NUDGE = math.sqrt(EPS32)
#: what ODE's ``dMessage`` says when its LCP solver fails in a step (lcp.cpp): then no iteration follows
LCP_FAILED = "LCP internal error"
#: a coupling whose nudge moves the residuals by less than this fraction of what its joints' own bodies predict
#: is locked (contacts or stops take the force): left out of the Newton step
LOCKED = 1e-3


@dataclass
class _Coupling:
    follower: JointHandle
    leader: JointHandle
    ratio: float
    offset: float
    warned: bool = False


class _Angle:
    """A hinge's angle unwrapped across ODE's +-pi (a mimic is the model's, not periodic)."""

    def __init__(self) -> None:
        self.last, self.turns = 0.0, 0

    def read(self, handle: JointHandle) -> float:
        angle = float(handle.joint.getAngle())
        self.turns -= round((angle - self.last) / (2.0 * math.pi))
        self.last = angle
        return angle + 2.0 * math.pi * self.turns


def _coordinate(handle: JointHandle, angles: dict[str, _Angle]) -> float:
    if handle.spec.kind is JointKind.HINGE:
        return angles[handle.spec.name].read(handle)
    return float(handle.joint.getPosition())


def resolution(handle: JointHandle, q: float) -> float:
    """The coordinate's float32 resolution as ODE computes it (module docstring, "Tolerance")."""
    if handle.spec.kind is JointKind.HINGE:
        return HINGE_RESOLUTION * EPS32 * max(1.0, abs(q))
    bodies = [handle.joint.getBody(0), handle.joint.getBody(1)]
    size = max(abs(q), *(b.getPosition().length() for b in bodies if b is not None and not b.isEmpty()))
    return SLIDER_RESOLUTION * EPS32 * size


def _push(handle: JointHandle, force: float) -> None:
    if handle.spec.kind is JointKind.HINGE:
        handle.joint.addTorque(force)
    else:
        handle.joint.addForce(force)


def check_mimics(world: CompiledWorld) -> None:
    """Refuse two couplings in one group of jointed bodies up front (module docstring)."""
    if len(world.couplings) < 2:
        return
    body_of = {spec.name: spec.body for spec in world.joints}
    dynamic = {b.name for b in world.bodies if b.motion is Motion.DYNAMIC}
    group = jointed_groups(world, {body_of[c.joint] for c in world.couplings} & dynamic)
    seen: dict[str, str] = {}
    for coupling in world.couplings:
        key = group.get(body_of[coupling.joint])
        if key is None:
            continue
        if key in seen:
            raise UnsupportedFeature(
                f"Backend `ode` holds one joint:mimic per group of jointed bodies: `{seen[key]}` and "
                f"`{coupling.joint}` share one; their force pairs, solved on trial steps, made ODE abort "
                '(docs/backends/ode.md, "Mimic joints")'
            )
        seen[key] = coupling.joint


class Mimics:
    """The world's couplings on ODE, each step solved for the force pair that holds them (module docstring)."""

    def __init__(self, world: CompiledWorld, scene: Scene, inertia: Callable[[JointHandle], float]) -> None:
        index = {handle.spec.name: handle for handle in scene.joints}
        self._couplings = []
        for coupling in world.couplings:
            ratio, offset = coupling.engine_terms(1.0, 1.0)  # ODE's coordinates are the world's
            self._couplings.append(_Coupling(index[coupling.joint], index[coupling.leader], ratio, offset))
        self._angles = {
            h.spec.name: _Angle()
            for c in self._couplings
            for h in (c.follower, c.leader)
            if h.spec.kind is JointKind.HINGE
        }
        self._bodies: list[OdeBody] = [b for b in scene.bodies if b is not None]
        self._inertia = inertia
        self._terms = np.zeros(len(self._couplings))
        self._slope: np.ndarray | None = None
        self.messages: list[str] = []

    def __bool__(self) -> bool:
        return bool(self._couplings)

    def step(self, issue: Callable[[], None], stepper: Callable[[float], None], h: float, t: float) -> None:
        """One ``dWorldStep`` that holds every coupling; ``issue`` adds the step's forces (ODE clears them)."""
        couplings = self._couplings
        leads = np.array([_coordinate(c.leader, self._angles) for c in couplings])
        follows = np.array([_coordinate(c.follower, self._angles) for c in couplings])
        ratios = np.array([c.ratio for c in couplings])
        asked = (ratios * leads + np.array([c.offset for c in couplings]) - follows) / h
        tolerance = np.array(
            [
                resolution(c.follower, qf) + abs(c.ratio) * resolution(c.leader, ql)
                for c, qf, ql in zip(couplings, follows, leads, strict=True)
            ]
        )
        speed = np.array([abs(motor_row_rate(c.follower)) + abs(c.ratio * motor_row_rate(c.leader)) for c in couplings])
        saved = [
            (b.getPosition(), Quat(b.getQuaternion()), b.getLinearVel(), b.getAngularVel()) for b in self._bodies
        ]
        seed = OdeUtil.randGetSeed()
        self.messages.extend(_native.take())  # what ODE said before the step's trials
        said: list[str] = []  # what ODE said in the last trial: the kept step's messages

        def trial(u: np.ndarray) -> np.ndarray:
            for body, (pos, quat, lin, ang) in zip(self._bodies, saved, strict=True):
                body.setPosition(pos)
                body.setQuaternion(quat)
                body.setLinearVel(lin)
                body.setAngularVel(ang)
            OdeUtil.randSetSeed(seed)
            issue()
            for c, force in zip(couplings, u, strict=True):
                _push(c.follower, float(force))
                _push(c.leader, -c.ratio * float(force))
            stepper(h)
            said[:] = _native.take()
            if any(LCP_FAILED in line for line in said):
                raise _Unsolved
            rates = [motor_row_rate(c.follower) - c.ratio * motor_row_rate(c.leader) for c in couplings]
            return np.array(rates) - asked

        inverse_inertia = np.array([self._inverse_inertia(c) for c in couplings])

        def nudge(residual: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            """Each term's nudge: it changes its coupling's rate by sqrt(eps32) of the rates' scale, or by the
            miss if that is larger (the slope then measured on the piece the correction lands on)."""
            rate = np.maximum(np.abs(residual), NUDGE * np.maximum(1.0, speed))
            return rate / (h * inverse_inertia), rate

        try:
            solved = solve_coupled_step(
                trial, self._terms, nudge, tolerance, h, ITERATIONS, LOCKED, self._slope, remeasure=False
            )
        except _Unsolved:  # the trial just taken is ODE's step, as it would be without the solve
            self.messages.extend(said)
            self._slope = None
            self._warn(None, tolerance, h, t)
            return
        self.messages.extend(said)
        self._terms, self._slope = solved.terms, solved.slope
        if not solved.held:
            self._warn(solved.residual, tolerance, h, t)

    def _inverse_inertia(self, coupling: _Coupling) -> float:
        """The coupling coordinate's inverse inertia from its joints' own bodies: the nudge's scale only."""
        return 1.0 / self._inertia(coupling.follower) + coupling.ratio**2 / self._inertia(coupling.leader)

    def _warn(self, residual: np.ndarray | None, tolerance: np.ndarray, h: float, t: float) -> None:
        """Say once per coupling that a step did not hold it (``residual`` None: ODE's LCP failed in the step)."""
        for k, c in enumerate(self._couplings):
            if c.warned or (residual is not None and h * abs(residual[k]) <= tolerance[k]):
                continue
            c.warned = True
            why = (
                "ODE's LCP solver failed in the step (its message above), so no force holds it there: the trial "
                "taken was kept"
                if residual is None
                else f"a step leaves it {h * abs(residual[k]):.3g} from its place (float32 tolerance "
                f"{tolerance[k]:.3g}); contacts or stops lock the coupled joints, and the step closest to the "
                "coupling was kept"
            )
            self.messages.append(
                f"joint:mimic `{c.follower.spec.name}` (of `{c.leader.spec.name}`) not held at t = {t:.6g} s: {why} "
                "(said once per coupling)"
            )


class _Unsolved(Exception):
    """ODE reported that its LCP solver failed in a trial: that step's rates are no affine function of the force."""
