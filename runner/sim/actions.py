"""Running handler actions (and interval action steps) against the host that owns the run's state.

The host is the step loop (:class:`runner.sim.session.Session`); actions see it only through
:class:`ActionHost`, so what an action may touch is written down here and nowhere else.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

from runner.errors import ScenarioError
from runner.language import model_actions as Act

MAX_SEND_DEPTH = 32


class IntervalControl(Protocol):
    """The play API of the scenario's intervals (Panda3D's ``ival.start()`` and friends)."""

    def start(self, ival: str, now: float) -> None: ...
    def pause(self, ival: str, now: float) -> float: ...
    def resume(self, ival: str, now: float) -> None: ...
    def finish(self, ival: str, now: float) -> None: ...
    def loop(self, ival: str, now: float) -> None: ...


class ActionHost(Protocol):
    """What handler actions may read and change."""

    ended: bool
    dt: float
    state: dict[str, Any]

    @property
    def intervals(self) -> IntervalControl: ...

    def truth(self, text: str) -> bool: ...
    def evaluate(self, text: str) -> Any: ...
    def play_sound(self, sound: str, offset: float, volume: float, loop: bool, at: float) -> None: ...
    def stop_sound(self, sound: str, at: float) -> None: ...
    def set_motor(self, joint: str, vel: float, fmax: float | None) -> None: ...
    def set_drive(self, command: Act.DriveCommand) -> None: ...
    def set_control(self, command: Act.ControlCommand) -> None: ...
    def add_force(self, body: str, force: Sequence[float], torque: Sequence[float], scale: float) -> None: ...
    def hold_force(self, command: Act.ApplyCommand, at: float) -> None: ...
    def reset(self, command: Act.ResetCommand) -> None: ...
    def log(self, at: float, level: str, message: str, name: str) -> None: ...
    def dispatch(self, event: str, at: float, source: str, depth: int = 0) -> None: ...
    def end(self, at: float, reason: str) -> None: ...


class ActionError(ScenarioError):
    """An action could not be carried out at run time (e.g. `send` recursing without end)."""


def run_actions(session: ActionHost, actions: Any, at: float, depth: int = 0) -> None:  # noqa: C901 - one dispatch
    for action in actions:
        if session.ended:
            return
        if isinstance(action, Act.IfAction):
            branch = action.then if session.truth(action.if_) else action.else_
            run_actions(session, branch, at, depth)
        elif isinstance(action, Act.StartAction):
            session.intervals.start(action.start, at)
        elif isinstance(action, Act.PauseAction):
            session.intervals.pause(action.pause, at)
        elif isinstance(action, Act.ResumeAction):
            session.intervals.resume(action.resume, at)
        elif isinstance(action, Act.FinishAction):
            session.intervals.finish(action.finish, at)
        elif isinstance(action, Act.LoopAction):
            session.intervals.loop(action.loop, at)
        elif isinstance(action, Act.SetAction):
            session.state.update(action.set)
        elif isinstance(action, Act.CalcAction):
            for var, text in action.calc.items():
                session.state[var] = session.evaluate(text)
        elif isinstance(action, Act.PlaySoundAction):
            session.play_sound(action.play_sound, 0.0, 1.0, False, at)
        elif isinstance(action, Act.StopSoundAction):
            session.stop_sound(action.stop_sound, at)
        elif isinstance(action, Act.MotorAction):
            session.set_motor(action.motor.joint, action.motor.vel, action.motor.fmax)
        elif isinstance(action, Act.DriveAction):
            session.set_drive(action.drive)
        elif isinstance(action, Act.ControlAction):
            session.set_control(action.control)
        elif isinstance(action, Act.ForceAction):
            session.add_force(action.force.body, action.force.value, action.force.torque, 1.0)
        elif isinstance(action, Act.ImpulseAction):
            # an impulse J over one step is the force J/dt for that step (semi-implicit Euler, exactly)
            session.add_force(action.impulse.body, action.impulse.value, action.impulse.torque, 1.0 / session.dt)
        elif isinstance(action, Act.ApplyAction):
            session.hold_force(action.apply, at)
        elif isinstance(action, Act.ResetAction):
            spec = action.reset
            session.reset(Act.ResetCommand(body=spec) if isinstance(spec, str) else spec)
        elif isinstance(action, Act.LogAction):
            message, level = (
                (action.log, "info") if isinstance(action.log, str) else (action.log.message, action.log.level)
            )
            session.log(at, level, message, "handler")
        elif isinstance(action, Act.SendAction):
            if depth >= MAX_SEND_DEPTH:
                raise ActionError(f"`send: {action.send}` nested deeper than {MAX_SEND_DEPTH} (a loop of events?)")
            session.dispatch(action.send, at, "send", depth + 1)
        elif isinstance(action, Act.EndAction):
            reason = action.end if isinstance(action.end, str) else "end action"
            if action.end is not False:
                session.end(at, reason)
