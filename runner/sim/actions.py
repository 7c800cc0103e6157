"""Running handler actions (and interval action steps) against a session."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from runner.errors import ScenarioError
from runner.language import model_behaviour as B
from runner.language.hpr import hpr_to_quat, quat_to_hpr

if TYPE_CHECKING:
    from runner.sim.session import Session

MAX_SEND_DEPTH = 32


class ActionError(ScenarioError):
    """An action could not be carried out at run time (e.g. `send` recursing without end)."""


def run_actions(session: Session, actions: Any, at: float, depth: int = 0) -> None:  # noqa: C901 - one dispatch
    for action in actions:
        if session.ended:
            return
        if isinstance(action, B.IfAction):
            branch = action.then if session.truth(action.if_) else action.else_
            run_actions(session, branch, at, depth)
        elif isinstance(action, B.StartAction):
            session.intervals.start(action.start, at)
        elif isinstance(action, B.PauseAction):
            session.intervals.pause(action.pause, at)
        elif isinstance(action, B.ResumeAction):
            session.intervals.resume(action.resume, at)
        elif isinstance(action, B.FinishAction):
            session.intervals.finish(action.finish, at)
        elif isinstance(action, B.LoopAction):
            session.intervals.loop(action.loop, at)
        elif isinstance(action, B.SetAction):
            session.state.update(action.set)
        elif isinstance(action, B.CalcAction):
            for var, text in action.calc.items():
                session.state[var] = session.evaluate(text)
        elif isinstance(action, B.PlaySoundAction):
            session.play_sound(action.play_sound, 0.0, 1.0, False, at)
        elif isinstance(action, B.StopSoundAction):
            session.stop_sound(action.stop_sound, at)
        elif isinstance(action, B.MotorAction):
            session.set_motor(action.motor.joint, action.motor.vel, action.motor.fmax)
        elif isinstance(action, B.ForceAction):
            session.add_force(action.force.body, action.force.value, action.force.torque, 1.0)
        elif isinstance(action, B.ImpulseAction):
            # an impulse J over one step is the force J/dt for that step (semi-implicit Euler, exactly)
            session.add_force(action.impulse.body, action.impulse.value, action.impulse.torque, 1.0 / session.dt)
        elif isinstance(action, B.ResetAction):
            _reset(session, action.reset)
        elif isinstance(action, B.LogAction):
            message, level = (
                (action.log, "info") if isinstance(action.log, str) else (action.log.message, action.log.level)
            )
            session.log(at, level, message, "handler")
        elif isinstance(action, B.SendAction):
            if depth >= MAX_SEND_DEPTH:
                raise ActionError(f"`send: {action.send}` nested deeper than {MAX_SEND_DEPTH} (a loop of events?)")
            session.dispatch(action.send, at, "send", depth + 1)
        elif isinstance(action, B.EndAction):
            reason = action.end if isinstance(action.end, str) else "end action"
            if action.end is not False:
                session.end(at, reason)


def _reset(session: Session, spec: str | B.ResetCommand) -> None:
    cmd = B.ResetCommand(body=spec) if isinstance(spec, str) else spec
    index = session.body_index[cmd.body]
    body = session.world.bodies[index]
    pos = cmd.pos if cmd.pos is not None else body.pos
    if cmd.quat is not None:
        quat = cmd.quat
    elif cmd.hpr is not None:
        quat = hpr_to_quat(cmd.hpr)
    else:
        quat = body.quat
    if body.motion.value == "kinematic":
        hpr = (
            cmd.hpr
            if cmd.hpr is not None
            else (quat_to_hpr(quat) if cmd.quat is not None else session.program.start_hpr[body.name])
        )
        session.kinematics.teleport(session.backend, body.name, pos, hpr)
    elif body.motion.value == "dynamic":
        session.backend.reset_body(index, pos, quat, cmd.vel, cmd.angvel)
