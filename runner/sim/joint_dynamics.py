"""Joint damping and dry friction (friction loss), engine-neutral: the joint's velocity motor commanded every step.

Before each step, for every slider or hinge with damping ``c`` or friction loss ``f`` that no motor or servo
of the scenario drives: ``set_motor(joint, 0, f + c |qdot|)``, ``qdot`` the joint's rate read after the last
step. The motor is a velocity constraint towards rest whose force is bounded by that amount, so

* friction loss is exact dry friction: the joint stays still while the other forces on it are below ``f``
  and otherwise slides against ``f`` (MuJoCo's frictionloss row, and ODE users' way of writing joint
  friction);
* damping is the force ``-c qdot`` with the rate taken at the start of the step, except that the motor never
  pushes the joint past rest: where ``c dt / m`` (``m`` the coordinate's effective inertia) would reverse the
  rate in one step, the joint stops instead. It is therefore stable for every ``c`` and ``dt`` (an explicit
  ``-c qdot`` torque diverges once ``c dt / m > 2``), and first-order accurate in ``dt`` like the step.

docs/semantics.md ("Joint dynamics") states the rules: the combination with a motor or a servo (the motor
wins), the effort and velocity limits (:func:`runner.compile.joints.capped`), and why MuJoCo running an
MJCF file keeps MuJoCo's own damping and friction loss for the file's joints, and DART and ODE their own damping.
"""

from __future__ import annotations

import math
from typing import Any

from backends.base import Backend
from backends.types import MODEL_FILE_CAPABILITIES, CompiledWorld
from runner.language.model import Scenario


def driven_joints(model: Scenario) -> set[str]:
    """The joints the scenario drives itself: a `motor` or a drive in velocity mode (hand-written or on a
    robot's joint) or a servo."""
    def motorised(o: Any) -> bool:
        return o.motor is not None or (o.drive is not None and o.drive.mode == "velocity")

    out = {name for name, joint in model.joints.items() if motorised(joint)}
    for rname, robot in model.robots.items():
        out.update(f"{rname}.{j}" for j, o in robot.joints.items() if motorised(o) or o.servo is not None)
    return out


def native_joints(world: CompiledWorld, backend: Backend) -> set[str]:
    """Joints whose damping and friction loss the engine runs itself: a model file's joints on an engine that
    builds robots from their file (MuJoCo: its own frictionloss row, the same constraint as this motor, and
    its implicit damping), with either options; a motor helper per joint would change its solver's scaling."""
    if not MODEL_FILE_CAPABILITIES <= backend.capabilities:
        return set()
    return {j for model in world.models for j in model.joints}


class JointFriction:
    """Commands the damping-and-friction motor of every joint that has one (module docstring)."""

    def __init__(self, world: CompiledWorld, skip: set[str], native_damping: bool = False) -> None:
        """``skip``: joints the scenario drives or the engine runs itself; ``native_damping``: the engine damps
        every joint itself (``Backend.native_damping``), the motor carries the friction loss only."""
        self.joints = [
            (k, spec.name, spec.dynamics.frictionloss, 0.0 if native_damping else spec.dynamics.damping)
            for k, spec in enumerate(world.joints)
            if spec.name not in skip
            and spec.kind.value in ("slider", "hinge")
            and (spec.dynamics.frictionloss > 0 or (spec.dynamics.damping > 0 and not native_damping))
        ]

    def __bool__(self) -> bool:
        return bool(self.joints)

    def release(self, joint: str) -> None:
        """The scenario commands this joint's motor from now on (a motor action): the motor is its own."""
        self.joints = [entry for entry in self.joints if entry[1] != joint]

    def drive(self, backend: Backend, velocities: list[float]) -> None:
        for k, _, friction, damping in self.joints:
            rate = velocities[k]
            if math.isfinite(rate):  # a NaN reading is the engine's failure, which the runner reports itself
                backend.set_motor(k, 0.0, friction + damping * abs(rate))
