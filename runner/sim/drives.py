"""Joint commands in position and torque mode (docs/semantics.md, "Joint commands"), engine-neutral.

Before each step k, for every slider or hinge commanded in position or torque mode, with the joint's
position ``q`` and rate ``qdot`` read after the last step (at t_k, from the joint's stated zero) and the
command's expressions read at t_k (``time`` = t_k):

* position: ``tau = kp (position - q) + kd (rate - qdot)``;
* torque: ``tau = torque``;

then ``tau`` is capped to ``[-effort, effort]`` where the joint has an effort limit, and held over the step
(every substep: a zero-order hold). A hinge gets it as the torque ``tau a`` on its body and ``-tau a`` on the
other (``a`` its axis now: the start axis turned with the body since the start), which is exactly the
generalised force ``tau`` on the hinge's coordinate; a slider as the force ``tau a`` at its body's centre of
mass and ``-tau a`` at the other's, plus the couple of the two lines of action shared by the two bodies (as
ODE's dJointAddSliderForce), so the pair adds no net force or moment to the system. The environment, and a
static or kinematic body, take nothing.

A position command integrated by the engines' semi-implicit Euler step h (substeps 1) is the recurrence
``v+ = v + h (kp e - kd v) / I``, ``q+ = q + h v+``: stable while ``kd h / I < 2`` and
``kp h^2 / I + 2 kd h / I < 4`` (I the coordinate's effective inertia), as an explicit PD law is.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from backends.geometry import quat_conj, quat_rotate
from backends.types import CompiledWorld, JointStates, Motion
from runner.language.model import Scenario
from runner.language.model_physics import Drive

#: (body index, world force, world torque) for the step
Wrench = tuple[int, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class _JointFrame:
    """What a joint's torque needs: its bodies (None: nothing to push), axis in its body's frame, kind."""

    owner: int  # the joint's body, whose orientation turns the axis
    body: int | None
    other: int | None
    axis_local: np.ndarray
    hinge: bool
    effort: float | None


def initial_drives(model: Scenario) -> dict[str, Drive]:
    """The joints commanded in position or torque mode at the start (velocity mode is the joint's motor)."""
    out = {name: j.drive for name, j in model.joints.items() if j.drive is not None and j.drive.mode != "velocity"}
    for rname, robot in model.robots.items():
        out.update(
            (f"{rname}.{jname}", j.drive)
            for jname, j in robot.joints.items()
            if j.drive is not None and j.drive.mode != "velocity"
        )
    return out


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` turned by the unit quaternion ``q`` (w, x, y, z)."""
    w, u = q[0], q[1:]
    return np.asarray(v + 2.0 * np.cross(u, np.cross(u, v) + w * v), dtype=float)


class Drives:
    """The position- and torque-mode commands acting now, by joint name."""

    def __init__(self, world: CompiledWorld, drives: dict[str, Drive]) -> None:
        index = {b.name: i for i, b in enumerate(world.bodies)}
        self.world = world
        self.joint_index = {j.name: k for k, j in enumerate(world.joints)}
        self.coms = np.asarray([b.com for b in world.bodies], dtype=float).reshape(-1, 3)
        self.frames: dict[int, _JointFrame] = {}
        for k, spec in enumerate(world.joints):
            if spec.kind.value not in ("slider", "hinge"):
                continue
            body = index[spec.body]
            other = index[spec.other] if spec.other is not None else None
            start = world.bodies[body].quat
            self.frames[k] = _JointFrame(
                body,
                body if world.bodies[body].motion is Motion.DYNAMIC else None,
                other if other is not None and world.bodies[other].motion is Motion.DYNAMIC else None,
                np.asarray(quat_rotate(quat_conj(start), spec.axis), dtype=float),
                spec.kind.value == "hinge",
                spec.dynamics.effort,
            )
        self.active: dict[int, Drive] = {}
        self.applied: dict[int, float] = {}  # joint -> the torque (force) handed out for the last step
        for name, drive in drives.items():
            self.set(name, drive)

    def __bool__(self) -> bool:
        return bool(self.active)

    def set(self, joint: str, drive: Drive) -> None:
        """Command ``joint`` in position or torque mode from the next step on."""
        self.active[self.joint_index[joint]] = drive

    def release(self, joint: str) -> bool:
        """The joint is commanded otherwise from now on (its motor); whether it had a command here."""
        return self.active.pop(self.joint_index[joint], None) is not None

    def torque(self, k: int, drive: Drive, q: float, qdot: float, number: Callable[[float | str], float]) -> float:
        """The command's torque (N m) or force (N) on joint ``k`` now, within its effort limit."""
        if drive.position is not None:
            kp = drive.kp if drive.kp is not None else 0.0
            tau = kp * (number(drive.position) - q) + drive.kd * (number(drive.rate) - qdot)
        else:
            tau = number(drive.torque if drive.torque is not None else 0.0)
        effort = self.frames[k].effort
        return tau if effort is None else max(-effort, min(effort, tau))

    def wrenches(
        self,
        pos: np.ndarray,
        quats: np.ndarray,
        positions: np.ndarray,
        rates: np.ndarray,
        number: Callable[[float | str], float],
        extra: dict[int, float] | None = None,
    ) -> list[Wrench]:
        """This step's forces and torques on the bodies, world frame at their centres of mass: the commands'
        and ``extra`` (joint -> torque, e.g. MJCF actuators' forces, runner.sim.actuators)."""
        out: list[Wrench] = []
        self.applied = {
            k: self.torque(k, d, float(positions[k]), float(rates[k]), number) for k, d in self.active.items()
        }
        for k, tau in (extra or {}).items():
            self.applied[k] = self.applied.get(k, 0.0) + tau
        for k, tau in self.applied.items():
            self.joint_wrenches(k, tau, pos, quats, out)
        return out

    def with_torques(self, joints: JointStates) -> JointStates:
        """``joints`` with the torque (force) handed out for the last step added to each commanded joint's motor
        force: `<joint>.force` reads the joint's actuation (itself if none)."""
        if not self.applied:
            return joints
        force = joints.motor_force.copy()
        for k, tau in self.applied.items():
            force[k] += tau
        return JointStates(joints.position, joints.velocity, force)

    def joint_wrenches(self, k: int, tau: float, pos: np.ndarray, quats: np.ndarray, out: list[Wrench]) -> None:
        """Joint ``k``'s torque (force) ``tau`` as the wrenches on its two bodies (module docstring)."""
        frame = self.frames[k]
        if not np.isfinite(tau) or frame.body is None and frame.other is None:
            return  # a NaN reading is the engine's failure, which the runner reports itself
        zero = np.zeros(3)
        axis = _rotate(np.asarray(quats[frame.owner], float), frame.axis_local)
        if frame.hinge:
            if frame.body is not None:
                out.append((frame.body, zero, tau * axis))
            if frame.other is not None:
                out.append((frame.other, zero, -tau * axis))
            return
        force = tau * axis
        centres = {
            i: np.asarray(pos[i], float) + _rotate(np.asarray(quats[i], float), self.coms[i])
            for i in (frame.body, frame.other)
            if i is not None
        }
        if frame.body is not None and frame.other is not None:
            couple = 0.5 * np.cross(centres[frame.body] - centres[frame.other], force)
            out.append((frame.body, force, -couple))
            out.append((frame.other, -force, -couple))
        elif frame.body is not None:
            out.append((frame.body, force, zero))
        elif frame.other is not None:
            out.append((frame.other, -force, zero))
