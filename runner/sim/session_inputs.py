"""What actions, handlers and intervals do to a running session (runner.sim.actions, runner.sim.intervals'
``IntervalHost``): expressions read now, kinematic targets, sounds, motors and joint commands, one-step and
held forces, resets, log lines. :class:`runner.sim.session.Session` is one; the step loop is there."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from backends.base import Backend
from backends.types import CompiledWorld, Motion
from runner.compile.joints import capped
from runner.compile.program import Program
from runner.language import model_actions as Act
from runner.language.hpr import hpr_to_quat, quat_to_hpr
from runner.sim.actuators import Actuators
from runner.sim.drives import Drives
from runner.sim.energy import EnergyWatch
from runner.sim.fluid import FluidForces
from runner.sim.held import HeldForces
from runner.sim.joint_dynamics import JointFriction
from runner.sim.kinematics import KinematicTable
from runner.sim.resolver import Snapshot, StateResolver


class SessionInputs:
    """The session's inputs from the scenario's behaviour; the attributes are the session's (its ``__init__``)."""

    program: Program
    backend: Backend
    trace: Any | None
    world: CompiledWorld
    names: list[str]
    body_index: dict[str, int]
    joint_index: dict[str, int]
    kinematics: KinematicTable
    snapshot: Snapshot
    resolver: StateResolver
    motors: dict[str, tuple[float, float]]
    drives: Drives
    actuators: Actuators
    native_actuators: bool
    joint_friction: JointFriction
    energy: EnergyWatch
    forces: dict[int, np.ndarray]
    held: HeldForces
    fluid: FluidForces
    playing_sounds: dict[str, float]
    sound_starts: list[tuple[float, str]]
    sound_stops: list[tuple[float, str]]

    def evaluate(self, text: str) -> Any:
        return self.program.expressions[text].evaluate(self.resolver)

    def truth(self, text: str) -> bool:
        return self.program.expressions[text].truth(self.resolver)

    def interval_event(self, ival: str, what: str, at: float) -> None:
        if self.trace is not None:
            self.trace.log(at, "debug", f"interval {ival}: {what}", "intervals")

    def log(self, at: float, level: str, message: str, name: str) -> None:
        if self.trace is not None:
            self.trace.log(at, level, message, name)

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

    def set_motor(self, joint: str, vel: float, fmax: float | None) -> None:
        fmax = self.motors[joint][1] if fmax is None else fmax
        self.motors[joint] = (vel, fmax)
        self.joint_friction.release(joint)  # the scenario's motor is the joint's from now on
        self.drives.release(joint)  # velocity mode: no position or torque command any more
        k = self.joint_index[joint]
        self.backend.set_motor(k, *capped(vel, fmax, self.world.joints[k].dynamics))

    def set_drive(self, command: Act.DriveCommand) -> None:
        """A joint's command from now on: velocity mode is its motor; position and torque mode turn the motor
        off and hand the engine a torque before every step (runner.sim.drives)."""
        if command.vel is not None:
            self.set_motor(command.joint, command.vel, command.fmax)
            return
        self.drives.set(command.joint, command)
        if self.motors[command.joint][1] > 0:
            self.motors[command.joint] = (0.0, 0.0)
            self.backend.set_motor(self.joint_index[command.joint], 0.0, 0.0)

    def set_control(self, command: Act.ControlCommand) -> None:
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

    def _fluid_forces(self) -> None:
        """The fluid's forces from the step's start, added to the step's forces (not through :meth:`add_force`: drag
        only takes energy away, and the energy check goes on; a wind turns it off in the step loop)."""
        forces, torques = self.fluid.wrenches(self.snapshot.bodies)
        for i, force, torque in zip(self.fluid.bodies.tolist(), forces, torques, strict=True):
            acc = self.forces.setdefault(i, np.zeros(6))
            acc[:3] += force
            acc[3:] += torque

    def hold_force(self, command: Act.ApplyCommand, at: float) -> None:
        steps = self.held.start(self.body_index[command.body], command)
        how = f"for {steps} steps" if steps is not None else f"until `{command.until}`"
        self.log(at, "debug", f"apply on `{command.body}`: held {how}", "handler")

    def reset(self, command: Act.ResetCommand) -> None:
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
