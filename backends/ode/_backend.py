"""OdeBackend: the reference backend, the Open Dynamics Engine itself through panda3d.ode (single precision).

Each engine step does what the lab's PyODE program does: collide, contact joints with the pair's surface,
forces of this scenario step (re-added for every substep: ODE clears them after each ``dWorldStep``),
``world.step`` or ``world.quickStep``, empty the contact group. Kinematic bodies are then put back
exactly on their commanded path and given their velocity again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from panda3d.core import Datagram

from ..base import Backend
from ..errors import BackendError, EngineFailure, map_engine_errors
from ..geometry import integrate_quat
from ..types import BodyStates, Capability, CompiledWorld, Contact, JointKind, JointStates, Motion, Quat, Vec3
from ._build import JointHandle, axis_arg, build_scene, destroy_scene, panda_quat, set_motor
from ._contacts import Collider
from ._options import OPTION_KEYS, parse_options

#: A dynamic body beyond these is a blow-up, reported as EngineFailure (m, m/s).
RUNAWAY_DISTANCE = 1e6
RUNAWAY_SPEED = 1e6
_ROTATIONAL = (JointKind.HINGE, JointKind.UNIVERSAL)


@dataclass
class _Kinematic:
    """A kinematic body's commanded pose (exact, float64) and velocity."""

    pos: np.ndarray
    quat: Quat
    lin: np.ndarray
    ang: np.ndarray


def _dot(a: Any, b: Any) -> float:
    return float(a[0] * b[0] + a[1] * b[1] + a[2] * b[2])


class OdeBackend(Backend):
    """Adapter to ODE: a faithful replay of the lab's PyODE program, the referee of the other backends."""

    name = "ode"
    engine_distribution = "panda3d"
    capabilities = frozenset(Capability)
    option_keys = OPTION_KEYS

    def __init__(self, world: CompiledWorld) -> None:
        super().__init__(world)
        self.options = parse_options(world.options_for(self.name))
        with map_engine_errors(self.name, "building the world"):
            self._scene = build_scene(world, self.options)
            self._collider = Collider(
                self._scene, self.options.collide, self.options.contact_forces, f"ode-contacts-{id(self):x}"
            )
            self._fudge = [j.joint.getParamFudgeFactor(*axis_arg(j)) if j.feedback else 1.0 for j in self._scene.joints]
        n = len(world.bodies)
        self._force = np.zeros((n, 3))
        self._torque = np.zeros((n, 3))
        self._pushed: set[int] = set()
        self._kinematic = {
            i: _Kinematic(np.array(b.pos, dtype=float), b.quat, np.array(b.lin_vel, dtype=float),
                          np.array(b.ang_vel, dtype=float))
            for i, b in enumerate(world.bodies)
            if b.motion is Motion.KINEMATIC
        }
        self._dynamic = [i for i, b in enumerate(world.bodies) if b.motion is Motion.DYNAMIC]
        self._dynamic_bodies = [self._scene.bodies[i] for i in self._dynamic]
        # Each body's state row (pos, quat, lin_vel, ang_vel): static rows set here, the others per read.
        self._fixed_rows = np.zeros((n, 13))
        for i, b in enumerate(world.bodies):
            if b.motion is Motion.STATIC:
                self._fixed_rows[i, 0:3], self._fixed_rows[i, 3:7] = b.pos, b.quat
        self._stepper = self._scene.world.step if self.options.stepper == "step" else self._scene.world.quickStep
        self._motor_force = np.zeros(len(world.joints))
        self._steps = 0
        self._states: BodyStates | None = None  # fresh states, dropped by anything that moves a body
        self._good: BodyStates | None = None  # the last states that passed the blow-up check
        self._closed = False

    def settings(self) -> dict[str, Any]:
        o = self.options
        return {
            "engine": "ODE via panda3d.ode (single precision)",
            "stepper": "dWorldStep" if o.stepper == "step" else "dWorldQuickStep",
            "quickstep_iterations": o.quickstep_iterations,
            "erp": o.erp,
            "cfm": o.cfm,
            "space": o.space,
            "collide": self._collider.mode,
            "contact_mode": "dContactBounce | dContactApprox1 (mu is a Coulomb coefficient)",
            "contact_forces": o.contact_forces,
            "kinematic": "body with gravity off and 1e6 x the heaviest mass, re-placed after each step",
        }

    # --- stepping ------------------------------------------------------------------------------------

    def step(self) -> None:
        self._require_open()
        world, scene, collider, stepper = self.world, self._scene, self._collider, self._stepper
        n, dt = world.substeps, world.dt
        h = dt / n
        joints, pushed, kinematic = scene.joints, self._pushed, self._kinematic
        motor = np.zeros(len(joints)) if joints else None
        with map_engine_errors(self.name, f"step at t={self._steps * dt:.6g} s"):
            for sub in range(n):
                last = sub == n - 1
                collider.collide(report=last)
                for i in pushed:
                    body = scene.bodies[i]
                    body.addForce(*self._force[i])  # type: ignore[union-attr]
                    body.addTorque(*self._torque[i])  # type: ignore[union-attr]
                if motor is None:
                    stepper(h)
                else:
                    limits = [self._limit(j) for j in joints]
                    stepper(h)
                    for k, (joint, limit) in enumerate(zip(joints, limits, strict=True)):
                        motor[k] += self._motor(k, joint, limit)
                collider.after_step(report=last)
                if kinematic:
                    self._place_kinematic(dt if last else h * (sub + 1), advance=last)
        if pushed:
            self._force[:] = 0.0
            self._torque[:] = 0.0
            pushed.clear()
        if motor is not None:
            self._motor_force = motor / n
        self._steps += 1
        self._states = self._good = self._check(self._read_rows())

    def _place_kinematic(self, t: float, *, advance: bool) -> None:
        """Put each kinematic body where its velocity takes it ``t`` after the step began."""
        for i, k in self._kinematic.items():
            pos = k.pos + k.lin * t
            quat = integrate_quat(k.quat, k.ang, t)
            body = self._scene.bodies[i]
            body.setPosition(*pos)  # type: ignore[union-attr]
            body.setQuaternion(panda_quat(quat))  # type: ignore[union-attr]
            body.setLinearVel(*k.lin)  # type: ignore[union-attr]
            body.setAngularVel(*k.ang)  # type: ignore[union-attr]
            if advance:
                k.pos, k.quat = pos, quat

    # --- motors --------------------------------------------------------------------------------------

    @staticmethod
    def _position(handle: JointHandle) -> tuple[float, float]:
        j, kind = handle.joint, handle.spec.kind
        if kind is JointKind.SLIDER:
            return j.getPosition(), j.getPositionRate()
        if kind is JointKind.HINGE:
            return j.getAngle(), j.getAngleRate()
        if kind is JointKind.UNIVERSAL:  # the first axis is the joint's coordinate
            return j.getAngle1(), j.getAngle1Rate()
        return math.nan, math.nan

    def _limit(self, handle: JointHandle) -> int:
        """ODE's limit state at the start of the step (dxJointLimitMotor::testRowActivation)."""
        spec = handle.spec
        if handle.fmax <= 0.0 or (spec.lo is None and spec.hi is None):
            return 0
        lo = -math.inf if spec.lo is None else spec.lo
        hi = math.inf if spec.hi is None else spec.hi
        if lo > hi or (spec.kind in _ROTATIONAL and lo < -math.pi and hi > math.pi):
            return 0
        pos = self._position(handle)[0]
        return 1 if pos <= lo else 2 if pos >= hi else 0

    def _motor(self, k: int, handle: JointHandle, limit: int) -> float:
        """The force (torque) the motor applied along the joint's coordinate in the step just taken.

        Off a stop the motor is an LCP row and joint feedback has its force; at a stop ODE applies
        +-fmax (times the fudge factor when powering away) directly to the bodies, outside feedback.
        """
        if handle.feedback is None or handle.fmax <= 0.0:
            return 0.0
        if limit:
            if handle.spec.lo == handle.spec.hi:
                return 0.0  # both stops at once: ODE switches the motor off
            fm = -handle.fmax if handle.vel > 0.0 or (handle.vel == 0.0 and limit == 2) else handle.fmax
            if (limit == 1 and handle.vel > 0.0) or (limit == 2 and handle.vel < 0.0):
                fm *= self._fudge[k]
            return -fm
        fb, j = handle.feedback, handle.joint
        force = fb.getForce1()
        if handle.spec.kind is JointKind.SLIDER:
            return _dot(force, j.getAxis())
        # Moment about the anchor: the anchor rows' forces have none, the motor row is along the axis.
        axis = j.getAxis() if handle.spec.kind is JointKind.HINGE else j.getAxis1()
        r = handle.body.getPosition() - j.getAnchor()
        return _dot(fb.getTorque1() + r.cross(force), axis)

    # --- reading -------------------------------------------------------------------------------------

    def _read_rows(self) -> np.ndarray:
        """All bodies' states, one (N, 13) array: each row pos, quat, lin_vel, ang_vel."""
        rows = self._fixed_rows.copy()
        for i, k in self._kinematic.items():  # the commanded pose, exact (ODE stores float32)
            row = rows[i]
            row[0:3], row[3:7], row[7:10], row[10:13] = k.pos, k.quat, k.lin, k.ang
        if self._dynamic:
            # Each vector written as ODE's float32 values (little-endian), widened to float64 exactly.
            dg = Datagram()
            for b in self._dynamic_bodies:
                b.getPosition().writeDatagramFixed(dg)  # type: ignore[union-attr]
                b.getQuaternion().writeDatagramFixed(dg)  # type: ignore[union-attr]
                b.getLinearVel().writeDatagramFixed(dg)  # type: ignore[union-attr]
                b.getAngularVel().writeDatagramFixed(dg)  # type: ignore[union-attr]
            rows[self._dynamic] = np.frombuffer(dg.getMessage(), dtype="<f4").reshape(-1, 13)
        return rows

    def _check(self, rows: np.ndarray) -> BodyStates:
        """The states of ``rows``, or EngineFailure when a body blew up (non-finite, or far or fast)."""
        states = BodyStates.from_rows(rows)
        # One look first: with no component above half the limits, every norm is below them (sqrt(3)/2 < 1).
        if rows.size and np.abs(rows).max() < 0.5 * min(RUNAWAY_DISTANCE, RUNAWAY_SPEED):
            return states
        bad = ~np.isfinite(states.pos).all(axis=1) | ~np.isfinite(states.lin_vel).all(axis=1)
        bad |= ~np.isfinite(states.quat).all(axis=1) | ~np.isfinite(states.ang_vel).all(axis=1)
        with np.errstate(invalid="ignore"):
            bad |= np.linalg.norm(states.pos, axis=1) > RUNAWAY_DISTANCE
            bad |= np.linalg.norm(states.lin_vel, axis=1) > RUNAWAY_SPEED
        if bad.any():
            i = int(np.argmax(bad))
            t = self._steps * self.world.dt
            last = self._good
            good = None if last is None else {"pos": last.pos[i].tolist(), "lin_vel": last.lin_vel[i].tolist()}
            raise EngineFailure(
                f"ode: body `{self.world.bodies[i].name}` blew up at t={t:.6g} s "
                f"(pos {states.pos[i].tolist()}, lin_vel {states.lin_vel[i].tolist()})",
                backend=self.name, body=self.world.bodies[i].name, time=t, last_good=good,
            )
        return states

    def body_states(self) -> BodyStates:
        self._require_open()
        if self._states is None:
            with map_engine_errors(self.name, "reading body states"):
                self._states = BodyStates.from_rows(self._read_rows())
        s = self._states
        return BodyStates(s.pos.copy(), s.quat.copy(), s.lin_vel.copy(), s.ang_vel.copy())

    def joint_states(self) -> JointStates:
        self._require_open()
        if not self._scene.joints:
            return JointStates(np.zeros(0), np.zeros(0), self._motor_force.copy())
        with map_engine_errors(self.name, "reading joint states"):
            read = [self._position(j) for j in self._scene.joints]
        m = len(read)
        pos = np.array([r[0] for r in read], dtype=float).reshape(m)
        vel = np.array([r[1] for r in read], dtype=float).reshape(m)
        return JointStates(pos, vel, self._motor_force.copy())

    def contacts(self) -> list[Contact]:
        self._require_open()
        return self._collider.contacts()

    # --- inputs --------------------------------------------------------------------------------------

    def _body(self, index: int, motion: Motion | None = None) -> Any:
        spec = self.world.bodies[index]
        if motion is not None and spec.motion is not motion:
            raise BackendError(f"ode: body `{spec.name}` is {spec.motion.value}, not {motion.value}.")
        return self._scene.bodies[index]

    def set_kinematic(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self._require_open()
        ode_body = self._body(body, Motion.KINEMATIC)
        k = _Kinematic(np.array(pos, dtype=float), tuple(quat), np.array(lin_vel, dtype=float),  # type: ignore[arg-type]
                       np.array(ang_vel, dtype=float))
        self._kinematic[body] = k
        with map_engine_errors(self.name, "placing a kinematic body"):
            ode_body.setPosition(*k.pos)
            ode_body.setQuaternion(panda_quat(k.quat))
            ode_body.setLinearVel(*k.lin)
            ode_body.setAngularVel(*k.ang)
        self._states = None

    def set_motor(self, joint: int, vel: float, fmax: float) -> None:
        self._require_open()
        with map_engine_errors(self.name, "setting a motor"):
            set_motor(self._scene.joints[joint], vel, fmax)

    def apply_force(self, body: int, force: Vec3, torque: Vec3) -> None:
        """Accumulated for the next step; kinematic and static bodies are unaffected by forces."""
        self._require_open()
        if self.world.bodies[body].motion is not Motion.DYNAMIC:
            return
        self._force[body] += force
        self._torque[body] += torque
        self._pushed.add(body)

    def reset_body(self, body: int, pos: Vec3, quat: Quat, lin_vel: Vec3, ang_vel: Vec3) -> None:
        self._require_open()
        if self.world.bodies[body].motion is Motion.KINEMATIC:
            self.set_kinematic(body, pos, quat, lin_vel, ang_vel)
            return
        ode_body = self._body(body, Motion.DYNAMIC)
        with map_engine_errors(self.name, "resetting a body"):
            ode_body.setPosition(*pos)
            ode_body.setQuaternion(panda_quat(quat))
            ode_body.setLinearVel(*lin_vel)
            ode_body.setAngularVel(*ang_vel)
        self._states = None

    # --- lifetime ------------------------------------------------------------------------------------

    def _require_open(self) -> None:
        if self._closed:
            raise BackendError("ode: the backend is closed.")

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            with map_engine_errors(self.name, "closing"):
                destroy_scene(self._scene)
