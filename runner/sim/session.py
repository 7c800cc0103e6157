"""One run of one scenario variant on one backend: the step loop (docs/semantics.md, "Step order").

Per step k, from t_k = k*dt to t_{k+1}:
 1. deliver events due at t_k: queued events (collisions seen at the end of the last step, in the order
    Panda3D's handler throws them) and timed inputs, to their handlers;
 2. step intervals to t_{k+1}: kinematic bodies get the pose they must have at the end of this step;
 3. give the engine each kinematic body's pose *and* velocity over the step; apply one-step forces, held
    forces and joint commands' torques (runner.sim.drives, runner.sim.actuators); motor targets were set by
    the handlers;
 4. physics step (with substeps if set);
 5. read states; detect contacts and collision-solid overlaps at t_{k+1};
 6. turn them into in / again / out events, then evaluate the condition triggers (runner.sim.conditions),
    all queued for step k+1 (delivered at t_{k+1}, the time of the state that raised them);
 7. record t_{k+1} in the trace; 8. check running assertions at t_{k+1}.
"""

from __future__ import annotations

import math
import time as wallclock
from collections import deque
from collections.abc import Callable, Generator, Sequence
from dataclasses import dataclass, field
from typing import Any, overload

import numpy as np

from backends.base import Backend
from backends.errors import EngineFailure
from backends.types import BodyStates, Capability, Motion
from runner import interrupts
from runner.compile.joints import capped
from runner.compile.program import Program
from runner.language import model_behaviour as B
from runner.language.hpr import hpr_to_quat, quat_to_hpr
from runner.sim.actions import run_actions
from runner.sim.actuators import Actuators
from runner.sim.assertions import AssertionTracker, Verdict
from runner.sim.budget import Watchdog
from runner.sim.collisions import EventHandler, SolidTraverser, quat_matrices
from runner.sim.conditions import ConditionTriggers, HandlerGate, JointZeros, with_zeros
from runner.sim.drives import Drives, initial_drives
from runner.sim.energy import EnergyWatch
from runner.sim.held import HeldForces
from runner.sim.intervals import IntervalManager
from runner.sim.joint_dynamics import JointFriction, driven_joints, native_joints
from runner.sim.kinematics import KinematicTable
from runner.sim.resolver import Snapshot, StateResolver
from runner.sim.servo import Servos, servo_specs

#: The one blow-up limit, for every engine (docs/semantics.md, "Blow-ups"): a body whose state is not finite,
#: or whose linear (m/s) or angular (rad/s) speed exceeds this, has blown up. Adapters check nothing
#: themselves beyond what their engine calls fatal (backends/base.py).
MAX_SPEED = 1.0e4


#: what ``Session.advance(pause=True)`` yields right before each engine step: the inputs of the step are set,
#: and a lockstep driver (runner.sim.lockstep) steps every world of a batch before the session goes on
BEFORE_STEP = "before-step"

_MAX_SPEED_SQUARED = MAX_SPEED * MAX_SPEED  # 1e8, exact: |v|^2 <= it  <=>  |v| <= MAX_SPEED (sqrt is monotone)
_FAST_LIMIT = _MAX_SPEED_SQUARED * (1.0 - 1e-9)  # the sums' fast test: far more than any rounding below the limit


def _blown_up(states: BodyStates) -> tuple[int, bool] | None:
    """The first body whose state is not finite or too fast, and whether it is not finite; None if none.

    Every step checks every body, so the common case (all well) is four whole-array calls: the sums of the
    squared speeds over all bodies bound each body's (a sum of non-negative terms is at least each of them;
    a NaN or an inf makes the sum fail the comparison, and the positions' and quaternions' sums are not
    finite when an element is not), held a little below the limit so that no rounding of the sums can let
    a body through. Anything else takes the exact per-body test.
    """
    lin, ang = states.lin_vel, states.ang_vel
    if not len(lin) or (
        float(np.vdot(lin, lin)) <= _FAST_LIMIT
        and float(np.vdot(ang, ang)) <= _FAST_LIMIT
        and math.isfinite(float(np.add.reduce(states.pos, axis=None)) + float(np.add.reduce(states.quat, axis=None)))
    ):
        return None
    lin2, ang2 = np.add.reduce(lin * lin, axis=1), np.add.reduce(ang * ang, axis=1)
    if (
        np.isfinite(states.pos).all()
        and np.isfinite(states.quat).all()
        and float(lin2.max()) <= _MAX_SPEED_SQUARED
        and float(ang2.max()) <= _MAX_SPEED_SQUARED
    ):
        return None
    bad = ~(
        np.isfinite(states.pos).all(axis=1)
        & np.isfinite(states.quat).all(axis=1)
        & np.isfinite(lin).all(axis=1)
        & np.isfinite(ang).all(axis=1)
    )
    fast = (np.linalg.norm(np.nan_to_num(lin, nan=np.inf), axis=1) > MAX_SPEED) | (
        np.linalg.norm(np.nan_to_num(ang, nan=np.inf), axis=1) > MAX_SPEED
    )
    broken = np.flatnonzero(bad | fast)
    if not broken.size:
        return None
    i = int(broken[0])
    return i, bool(bad[i])


@dataclass
class RunResult:
    scenario: str
    variant: str
    backend: str
    status: str  # passed | failed | engine-failure | interrupted
    verdicts: list[Verdict]
    end_time: float
    steps: int
    events: list[tuple[float, str, str]]
    sounds: list[tuple[float, str]]
    wall_seconds: float
    trace: str | None = None
    failure: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    engine_messages: int = 0  # lines the engine printed about itself (Backend.drain_messages), in the trace log

    @property
    def passed(self) -> bool:
        return self.status == "passed"


class Session:
    def __init__(
        self,
        program: Program,
        backend: Backend,
        trace: Any | None = None,
        progress: Callable[[int, int], None] | None = None,
        record_every: int = 1,
        watchdog: Watchdog | None = None,
    ) -> None:
        self.program = program
        self.watchdog = watchdog  # the wall-clock budget, checked after each step (runner.sim.budget)
        self.record_every = max(1, int(record_every))  # the trace gets every k-th step (and the last)
        self._recorded: float | None = None  # time of the last step in the trace
        self.world = program.world
        self.backend = backend
        self.trace = trace
        self.progress = progress
        self.dt = self.world.dt
        self.names = [b.name for b in self.world.bodies]
        self.body_index = {b.name: i for i, b in enumerate(self.world.bodies)}
        self.joint_index = {j.name: i for i, j in enumerate(self.world.joints)}
        model = program.loaded.model
        self.state: dict[str, Any] = dict(model.state)
        self.motors = {j.name: (j.motor.vel, j.motor.fmax) if j.motor else (0.0, 0.0) for j in self.world.joints}
        self.kinematics = KinematicTable(self.world, program.start_hpr, program.start_scale)
        self.intervals = IntervalManager(self, program.intervals)
        self.snapshot = Snapshot()
        self._contact_pairs: set[tuple[str, str]] | None = set()  # None: not yet made from self.contacts
        self.contacts: list[Any] = []
        self._contacts_at: float | None = None  # when self.contacts was read
        # Contacts are read every step only when something uses them: contact events, contact() in an
        # expression, a contact assertion; otherwise only for the steps the trace records.
        self._contacts_always = (
            bool(program.contact_colliders)
            or any("contact" in e.calls for e in program.expressions.values())
            or any(type(a).__name__ == "ContactAssertion" for a in model.assertions)
        )
        self.events: list[tuple[float, str, str]] = []
        self.engine_messages = 0
        self.event_counts: dict[str, int] = {}
        self.sound_starts: list[tuple[float, str]] = []
        self.sound_stops: list[tuple[float, str]] = []
        self.playing_sounds: dict[str, float] = {}
        self.forces: dict[int, np.ndarray] = {}
        self.held = HeldForces(self.dt, [b.com for b in self.world.bodies])  # `apply` (runner.sim.held)
        self.queue: deque[tuple[str, str]] = deque()
        self.injected: list[str] = []  # input events for the next step boundary (inject(); scenario view)
        self.ended = False
        self.end_reason = ""
        self.resolver = StateResolver(
            self.world,
            program.groups,
            self.state,
            dict(model.params),
            self.snapshot,
            {
                "contact": lambda a: self.in_contact(str(a[0]), str(a[1])),
                "playing": lambda a: self.intervals.is_playing(str(a[0])),
                "count": lambda a: self.event_counts.get(str(a[0]), 0),
            },
            eps=backend.precision.eps,
            frames=program.frames,
        )
        self.tracker = AssertionTracker(model.assertions, program.expressions, backend.name, self.dt)
        self.traverser = SolidTraverser(program.nodes, program.colliders)
        c = model.collisions
        self.collision_events = EventHandler(c.in_, c.again, c.out)
        self.conditions = ConditionTriggers(program.triggers, program.expressions)
        self.handler_gate = HandlerGate()
        self._zeros = JointZeros([(self.joint_index[j], offset) for j, offset in program.joint_zeros.items()])
        self.servos = Servos(servo_specs(model), self.joint_index, self.world)  # position servos (sim.servo)
        self.drives = Drives(self.world, initial_drives(model))  # position and torque commands (sim.drives)
        self.actuators = Actuators(model, program.loaded.robots, self.joint_index)  # MJCF actuators (sim.actuators)
        self.native_actuators = Capability.ACTUATOR_NATIVE in backend.capabilities  # the engine runs the file's
        # damping and friction loss as each joint's motor (runner.sim.joint_dynamics)
        self.joint_friction = JointFriction(
            self.world, driven_joints(model) | native_joints(self.world, backend), backend.native_damping
        )
        # energy from nowhere: exit 3 (runner.sim.energy)
        self.energy = EnergyWatch(self.world, backend.name, program.joint_zeros)

    # --- services used by actions and intervals (runner.sim.intervals.IntervalHost) --------------------
    def evaluate(self, text: str) -> Any:
        return self.program.expressions[text].evaluate(self.resolver)

    def truth(self, text: str) -> bool:
        return self.program.expressions[text].truth(self.resolver)

    @property
    def contact_pairs(self) -> set[tuple[str, str]]:
        """The touching pairs by name, made from the last contacts read when something first asks."""
        if self._contact_pairs is None:
            names = self.names
            self._contact_pairs = {(names[c.a], names[c.b]) for c in self.contacts}
        return self._contact_pairs

    def in_contact(self, a: str, b: str) -> bool:
        pairs = self.contact_pairs
        return (a, b) in pairs or (b, a) in pairs

    def get_pos(self, body: str) -> tuple[float, float, float]:
        return self.kinematics.get(body).target_pos

    def get_hpr(self, body: str) -> tuple[float, float, float]:
        return self.kinematics.get(body).target_hpr

    def get_scale(self, body: str) -> float:
        return self.kinematics.get(body).target_scale

    def set_pos(self, body: str, pos: Sequence[float]) -> None:
        self.kinematics.get(body).target_pos = (float(pos[0]), float(pos[1]), float(pos[2]))

    def set_hpr(self, body: str, hpr: Sequence[float]) -> None:
        self.kinematics.get(body).target_hpr = (float(hpr[0]), float(hpr[1]), float(hpr[2]))

    def set_scale(self, body: str, scale: float) -> None:
        self.kinematics.get(body).target_scale = float(scale)

    def run_actions(self, actions: Any, at: float) -> None:
        run_actions(self, actions, at)

    def play_sound(self, sound: str, offset: float, volume: float, loop: bool, at: float) -> None:
        if sound in self.playing_sounds:
            self.sound_stops.append((at, sound))
            if self.trace is not None:
                self.trace.sound(at, sound, "stop")  # a replay restarts the sound (OpenAL play() stops first)
        length = self.program.sounds[sound].length
        self.playing_sounds[sound] = math.inf if loop else at + max(length - offset, 0.0)
        self.sound_starts.append((at, sound))
        if self.trace is not None:
            self.trace.sound(at, sound, "start", offset, volume)

    def stop_sound(self, sound: str, at: float) -> None:
        if self.playing_sounds.pop(sound, None) is not None:
            self.sound_stops.append((at, sound))
            if self.trace is not None:
                self.trace.sound(at, sound, "stop")

    def interval_event(self, ival: str, what: str, at: float) -> None:
        if self.trace is not None:
            self.trace.log(at, "debug", f"interval {ival}: {what}", "intervals")

    def set_motor(self, joint: str, vel: float, fmax: float | None) -> None:
        fmax = self.motors[joint][1] if fmax is None else fmax
        self.motors[joint] = (vel, fmax)
        self.joint_friction.release(joint)  # the scenario's motor is the joint's from now on
        self.drives.release(joint)  # velocity mode: no position or torque command any more
        k = self.joint_index[joint]
        self.backend.set_motor(k, *capped(vel, fmax, self.world.joints[k].dynamics))

    def set_drive(self, command: B.DriveCommand) -> None:
        """A joint's command from now on: velocity mode is its motor; position and torque mode turn the motor
        off and hand the engine a torque before every step (runner.sim.drives)."""
        if command.vel is not None:
            self.set_motor(command.joint, command.vel, command.fmax)
            return
        self.drives.set(command.joint, command)
        if self.motors[command.joint][1] > 0:
            self.motors[command.joint] = (0.0, 0.0)
            self.backend.set_motor(self.joint_index[command.joint], 0.0, 0.0)

    def set_control(self, command: B.ControlCommand) -> None:
        """An MJCF actuator's `ctrl` from now on (runner.sim.actuators)."""
        self.actuators.set(command.actuator, command.ctrl)

    def _command_joints(self) -> None:
        """The position and torque commands, and the MJCF actuators, before the step (runner.sim.drives)."""
        snap = self.snapshot
        extra: dict[int, float] = {}
        if self.actuators and self.native_actuators:
            self.energy.driven()  # the engine's actuators do work the check does not book
            self.actuators.drive_native(self.backend, self._number)
        elif self.actuators:
            extra = self.actuators.torques(snap.joints.position.tolist(), snap.joints.velocity.tolist(), self._number)
        for i, force, torque in self.drives.wrenches(
            snap.bodies.pos, snap.bodies.quat, snap.joints.position, snap.joints.velocity, self._number, extra
        ):
            self.add_force(self.names[i], force.tolist(), torque.tolist(), 1.0)

    def _number(self, value: float | str) -> float:
        """A command's number, or its expression's value now."""
        return float(self.program.expressions[value].number(self.resolver)) if isinstance(value, str) else value

    def add_force(self, body: str, force: Sequence[float], torque: Sequence[float], scale: float) -> None:
        i = self.body_index[body]
        acc = self.forces.setdefault(i, np.zeros(6))
        self.energy.driven()  # a force's work is not booked: the energy check starts afresh after this step
        acc[:3] += np.asarray(force, float) * scale
        acc[3:] += np.asarray(torque, float) * scale

    def hold_force(self, command: B.ApplyCommand, at: float) -> None:
        steps = self.held.start(self.body_index[command.body], command)
        how = f"for {steps} steps" if steps is not None else f"until `{command.until}`"
        self.log(at, "debug", f"apply on `{command.body}`: held {how}", "handler")

    def reset(self, command: B.ResetCommand) -> None:
        """The lab's reset: a dynamic body teleported with new velocities, a kinematic one moved to a pose."""
        index = self.body_index[command.body]
        body = self.world.bodies[index]
        self.energy.driven()
        pos = command.pos if command.pos is not None else body.pos
        if command.quat is not None:
            quat = command.quat
        elif command.hpr is not None:
            quat = hpr_to_quat(command.hpr)
        else:
            quat = body.quat
        if body.motion is Motion.KINEMATIC:
            if command.hpr is not None:
                hpr = command.hpr
            else:
                hpr = quat_to_hpr(quat) if command.quat is not None else self.program.start_hpr[body.name]
            self.kinematics.teleport(self.backend, body.name, pos, hpr)
        elif body.motion is Motion.DYNAMIC:
            self.backend.reset_body(index, pos, quat, command.vel, command.angvel)

    def log(self, at: float, level: str, message: str, name: str) -> None:
        if self.trace is not None:
            self.trace.log(at, level, message, name)

    def dispatch(self, event: str, at: float, source: str, depth: int = 0) -> None:
        """Deliver an event to its handler now (Panda3D's messenger.send is synchronous)."""
        self.events.append((at, event, source))
        self.event_counts[event] = self.event_counts.get(event, 0) + 1
        if self.trace is not None:
            self.trace.event(at, event, source)
        handler = self.program.handlers.get(event)
        if handler is None or not handler.actions:
            return
        refusal = self.handler_gate.refusal(event, handler, at)
        if refusal is not None:
            self.log(at, "debug", refusal, "handler")
            return
        run_actions(self, handler.actions, at, depth)

    def end(self, at: float, reason: str) -> None:
        self.ended = True
        self.end_reason = reason
        self.log(at, "info", f"scenario ended: {reason}", "scenario")

    # --- the loop --------------------------------------------------------------------------------
    def _last_good(self, i: int) -> dict[str, Any] | None:
        """Body ``i``'s last state that passed the checks, as every engine failure reports it."""
        last = self.snapshot.bodies
        if not len(last.pos):  # nothing read yet
            return None
        return {
            "time": self.snapshot.time,
            "pos": last.pos[i].tolist(),
            "vel": last.lin_vel[i].tolist(),
            "angvel": last.ang_vel[i].tolist(),
        }

    def _step(self, t_next: float) -> None:
        """The engine's step; a blow-up the engine detects itself gets the same record as the runner's."""
        try:
            self.backend.step()
        except EngineFailure as exc:
            if exc.body in self.body_index:
                exc.last_good = self._last_good(self.body_index[exc.body])
                exc.time = t_next if exc.time is None else exc.time
            self._log_engine_messages(t_next)
            raise
        self._log_engine_messages(t_next)

    def _log_engine_messages(self, t: float) -> None:
        """What the engine printed about itself (ODE's LCP messages...) goes to the trace's log, counted."""
        for line in self.backend.drain_messages():
            self.engine_messages += 1
            self.log(t, "warning", line, "engine")

    def _read(self, t: float, contacts: bool = True) -> None:
        states = self.backend.body_states()
        broken = _blown_up(states)
        if broken is not None:
            i, bad = broken
            name = self.world.bodies[i].name
            what = "a non-finite state" if bad else f"a speed above {MAX_SPEED:g}"
            raise EngineFailure(
                f"body `{name}` reached {what} at t={t:.4f} s on {self.backend.name}",
                backend=self.backend.name,
                body=name,
                time=t,
                last_good=self._last_good(i),
            )
        joints = with_zeros(self.backend.joint_states(), self._zeros)  # stated zeros (compile.joints)
        joints = self.drives.with_torques(joints)  # `<joint>.force` includes a drive's torque (sim.drives)
        try:
            self.energy.check(t, states, joints)
        except EngineFailure as exc:
            exc.last_good = self._last_good(self.body_index[exc.body]) if exc.body in self.body_index else None
            raise
        self.snapshot.time = t
        self.snapshot.bodies = states
        self.snapshot.joints = joints
        if self.world.reaction_joints:  # only the joints the scenario reads (runner.compile.sensed)
            self.snapshot.reactions = self.backend.joint_reactions()
        if contacts or self._contacts_always:
            self._read_contacts(t)

    def _read_contacts(self, t: float) -> None:
        self.contacts = self.backend.contacts()
        self._contact_pairs = None
        self._contacts_at = t

    def _solid_hits(self) -> list[tuple[str, str, bool]]:
        s = self.snapshot.bodies
        scale = np.array([k.scale for k in self.kinematics.by_name.values()])  # world order
        return self.traverser.traverse_arrays(s.pos, quat_matrices(s.quat), scale)

    def _detect(self, t: float) -> None:
        hits = self._solid_hits() if self.traverser.colliders else []
        names = self.names
        if self.program.contact_colliders:
            touching: dict[int, list[int]] = {}  # body -> the bodies it touches, in contact order
            for c in self.contacts:
                touching.setdefault(c.a, []).append(c.b)
                touching.setdefault(c.b, []).append(c.a)
            for i in self.program.contact_colliders:
                hits.extend((names[i], names[other], True) for other in touching.get(i, ()))
        if hits or self.collision_events.last:  # nothing touching now or before: no in, again or out event
            for ev in self.collision_events.update(hits):
                self.queue.append((ev.name, f"collision-{ev.kind}"))
        for event in self.conditions.check(self.resolver):  # after the collision events of the same step
            self.queue.append((event, "condition"))

    def _record(self, t: float, k: int = 0, last: bool = False) -> None:
        """Step ``k`` ends at ``t``: sounds that ended, the trace (every ``record_every``-th step and the
        last), running assertions (every step)."""
        for name, end in list(self.playing_sounds.items()) if self.playing_sounds else ():
            if end <= t + 1e-9:
                del self.playing_sounds[name]
                self.sound_stops.append((end, name))
                if self.trace is not None:
                    self.trace.sound(end, name, "stop")
        if self.trace is not None and (k % self.record_every == 0 or last):
            self._trace_step(t)
        self.tracker.on_step(t, self.resolver, self.in_contact)
        self._log_verdicts(t)

    def _log_verdicts(self, t: float) -> None:
        """Log the verdicts the tracker decided, at ``t``, the time they were decided."""
        if not self.tracker.decided:
            return
        decided = self.tracker.pop_decided()
        if self.trace is not None:
            for v in decided:
                self.trace.verdict(t, v.as_dict())

    def _trace_step(self, t: float) -> None:
        trace = self.trace
        if trace is None:
            return
        if self._contacts_at != t:
            self._read_contacts(t)
        if self.kinematics.scale_changed:
            start = self.program.start_scale
            trace.scene(t, scales={n: k.scale / start[n] for n, k in self.kinematics.by_name.items()})
            self.kinematics.scale_changed.clear()
        trace.step(t, self.snapshot.bodies, self.snapshot.joints, self.contacts, self.state)
        if self.world.contact_points:  # the scenario's trace.contact_points: read only when asked (costly)
            trace.contact_points(t, self.backend.contact_points())
        if self.program.sensors:  # the sensor quantities the scenario reads (docs/trace-format.md, /sensors)
            trace.sensors(t, [self.resolver.value(name) for name in self.program.sensors])
        self._recorded = t

    def run(self) -> RunResult:
        """Run every step; the result."""
        steps = self.advance()
        while True:
            try:
                next(steps)
            except StopIteration as done:
                return done.value

    def inject(self, event: str) -> None:
        """Deliver ``event`` at the next step boundary exactly as a timed input due there would be (source
        "input", after the timed inputs of that step): how a live run (scenario view) gets keys and clicks."""
        self.injected.append(event)

    @overload
    def advance(self) -> Generator[float, None, RunResult]: ...

    @overload
    def advance(self, pause: bool) -> Generator[float | str, None, RunResult]: ...

    def advance(self, pause: bool = False) -> Generator[float | str, None, RunResult]:
        """The step loop, one step at a time: yields the simulated time reached (0 before the first step,
        then after each step), returns the result. ``run()`` drains it; a live run paces it. ``pause``: also
        yields :data:`BEFORE_STEP` right before each engine step (the lockstep of a world batch)."""
        start = wallclock.perf_counter()
        steps = self.program.steps
        inputs = deque(self.program.inputs)
        self._log_engine_messages(0.0)
        self._read(0.0)
        self.conditions.start(self.resolver)  # the conditions' values at t=0: a rising edge needs false first
        self._record(0.0)
        self.queue.append(("start", "start"))
        t = 0.0
        k = 0
        yield t
        for k in range(steps):
            t = k * self.dt
            if self.queue or self.injected or (inputs and inputs[0].step <= k):  # events due at t
                pending = list(self.queue)
                self.queue.clear()
                while inputs and inputs[0].step <= k:
                    pending.append((inputs.popleft().event, "input"))
                pending.extend((event, "input") for event in self.injected)
                self.injected.clear()
                for event, source in pending:
                    self.dispatch(event, t, source)
                    if self.ended:
                        break
            if self.ended:
                break
            t_next = (k + 1) * self.dt
            self.intervals.step(t_next)
            if self.kinematics.drive(self.backend, self.dt):
                self.energy.driven()  # a moving kinematic body pushes what it touches: unbooked work
            if self.held:
                for i, force, torque in self.held.step_inputs(self.snapshot.bodies.quat, self.truth):
                    self.add_force(self.names[i], force.tolist(), torque.tolist(), 1.0)
            if self.drives or self.actuators:
                self._command_joints()
            elif self.drives.applied:
                self.drives.applied = {}  # the last command ended: the joint's force is its motor's again
            for i, f in self.forces.items():
                self.backend.apply_force(i, tuple(f[:3]), tuple(f[3:]))
            self.forces.clear()
            if self.servos:
                self.servos.drive(self.backend, self.snapshot.joints.position.tolist(), self.resolver)
            if self.joint_friction:
                self.joint_friction.drive(self.backend, self.snapshot.joints.velocity.tolist())
            if pause:
                yield BEFORE_STEP
            self._step(t_next)
            recorded = self.trace is not None and ((k + 1) % self.record_every == 0 or k == steps - 1)
            self._read(t_next, contacts=recorded)
            self._detect(t_next)
            self._record(t_next, k + 1, last=k == steps - 1)
            interrupts.check()  # a SIGINT/SIGTERM that came during this step: the trace ends with it whole
            if self.watchdog is not None:
                self.watchdog.check(k + 1)
            t = t_next
            if self.progress is not None and (k % 50 == 0 or k == steps - 1):
                self.progress(k + 1, steps)
            yield t
        else:
            k = steps
        if self.trace is not None and self._recorded != t:  # ended between recorded steps: keep the last state
            self._trace_step(t)
        self.tracker.on_step(t, self.resolver, self.in_contact, final=True)
        verdicts = self.tracker.finish(
            t, [(e[0], e[1]) for e in self.events], self.sound_starts, self.resolver, self.sound_stops
        )
        self._log_verdicts(t)
        status = "passed" if all(v.passed for v in verdicts) else "failed"
        return RunResult(
            self.program.name,
            self.program.loaded.variant,
            self.backend.name,
            status,
            verdicts,
            t,
            k,
            self.events,
            self.sound_starts,
            wallclock.perf_counter() - start,
            engine_messages=self.engine_messages,
        )
