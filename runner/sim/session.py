"""One run of one scenario variant on one backend: the step loop (docs/semantics.md, "Step order").

Per step k, from t_k = k*dt to t_{k+1}:
 1. deliver events due at t_k: queued events (collisions seen at the end of the last step, in the order
    Panda3D's handler throws them) and timed inputs, to their handlers;
 2. step intervals to t_{k+1}: kinematic bodies get the pose they must have at the end of this step;
 3. give the engine each kinematic body's pose *and* velocity over the step; apply one-step forces, held
    forces, joint commands' torques (runner.sim.drives, runner.sim.actuators) and the fluid's forces
    (runner.sim.fluid); motor targets were set by the handlers;
 4. physics step (with substeps if set);
 5. read states; detect contacts and collision-solid overlaps at t_{k+1};
 6. turn them into in / again / out events, then evaluate the condition triggers (runner.sim.conditions),
    all queued for step k+1 (delivered at t_{k+1}, the time of the state that raised them);
 7. record t_{k+1} in the trace; 8. check running assertions at t_{k+1}.
"""

from __future__ import annotations

import time as wallclock
from collections import deque
from collections.abc import Callable, Generator
from typing import Any, overload

import numpy as np

from backends.base import Backend
from backends.errors import EngineFailure
from backends.types import MODEL_FILE_CAPABILITIES, Capability
from runner import interrupts
from runner.compile.program import Program
from runner.sim.actions import run_actions
from runner.sim.actuators import Actuators
from runner.sim.assertions import AssertionTracker
from runner.sim.blowup import MAX_SPEED, blown_up, last_good
from runner.sim.budget import Watchdog
from runner.sim.collisions import EventHandler, SolidTraverser, quat_matrices
from runner.sim.conditions import ConditionTriggers, HandlerGate, JointZeros, with_zeros
from runner.sim.drives import Drives, initial_drives
from runner.sim.energy import EnergyWatch
from runner.sim.fluid import FluidForces
from runner.sim.held import HeldForces
from runner.sim.intervals import IntervalManager
from runner.sim.joint_dynamics import JointFriction, driven_joints, native_joints
from runner.sim.kinematics import KinematicTable
from runner.sim.resolver import Snapshot, StateResolver
from runner.sim.result import RunResult
from runner.sim.servo import Servos, servo_specs
from runner.sim.session_inputs import SessionInputs

#: what ``Session.advance(pause=True)`` yields right before each engine step: the inputs of the step are set,
#: and a lockstep driver (runner.sim.lockstep) steps every world of a batch before the session goes on
BEFORE_STEP = "before-step"


class Session(SessionInputs):
    """The step loop over one backend; what the scenario's behaviour does to it is :class:`SessionInputs`."""

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
        # the MJCF file's fluid: MuJoCo runs it from the file (its <option>, with either options), the runner
        # everywhere else
        self.fluid = FluidForces(self.world, native=MODEL_FILE_CAPABILITIES <= backend.capabilities)

    # --- what conditions and assertions read ------------------------------------------------------
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

    def run_actions(self, actions: Any, at: float) -> None:
        run_actions(self, actions, at)

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
    def _step(self, t_next: float) -> None:
        """The engine's step; a blow-up the engine detects itself gets the same record as the runner's."""
        try:
            self.backend.step()
        except EngineFailure as exc:
            if exc.body in self.body_index:
                exc.last_good = last_good(self.snapshot, self.body_index[exc.body])
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
        broken = blown_up(states)
        if broken is not None:
            i, bad = broken
            name = self.world.bodies[i].name
            what = "a non-finite state" if bad else f"a speed above {MAX_SPEED:g}"
            raise EngineFailure(
                f"body `{name}` reached {what} at t={t:.4f} s on {self.backend.name}",
                backend=self.backend.name,
                body=name,
                time=t,
                last_good=last_good(self.snapshot, i),
            )
        joints = with_zeros(self.backend.joint_states(), self._zeros)  # stated zeros (compile.joints)
        joints = self.drives.with_torques(joints)  # `<joint>.force` includes a drive's torque (sim.drives)
        self.energy.check(t, states, joints)  # a gain raises EnergyGain with the state before it
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
        try:
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
                if self.fluid:
                    self._fluid_forces()
                if self.fluid.adds_energy:
                    self.energy.driven()  # a wind's work is not booked: the check starts afresh after this step
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
        except GeneratorExit:
            raise
        except BaseException:
            # the energy check's last steps first: a gain there came before this failure (runner.sim.energy)
            self.energy.flush()
            raise
        self.energy.flush()
        if self.trace is not None and self._recorded != t:  # ended between recorded steps: keep the last state
            self._trace_step(t)
        self.tracker.on_step(t, self.resolver, self.in_contact, final=True)
        verdicts = self.tracker.finish(
            t, [(e[0], e[1]) for e in self.events], self.sound_starts, self.resolver, self.sound_stops
        )
        self._log_verdicts(t)
        status = "passed" if all(v.passed for v in verdicts) else "failed"
        return RunResult(self.program.name, self.program.loaded.variant, self.backend.name, status, verdicts, t, k,
                         self.events, self.sound_starts, wallclock.perf_counter() - start,
                         engine_messages=self.engine_messages)  # fmt: skip
