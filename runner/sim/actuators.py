"""MJCF actuators driven by name (`actuators:` on a robot, the `control` action; docs/robots.md, "MJCF
actuators").

On an engine that builds the MJCF file itself (MuJoCo) the file's own actuator runs: its `ctrl` is set
before every step (``Backend.set_control``), and MuJoCo clamps it and computes the force, as the file runs.
Elsewhere the runner applies MuJoCo's force law for an actuator on a hinge or slide with a fixed gain, an
affine (or no) bias and no activation dynamics. Before every step, with the joint's q and qdot read after
the last step (from the model's zero) and `ctrl` read then:

    c = clamp(ctrl, ctrlrange);  f = gain c + b0 + b1 gear q + b2 gear qdot;  f = clamp(f, forcerange)

and the joint gets the torque (force) gear f as a torque-mode command does (runner.sim.drives), held over the
step. So a `<motor>` gives gear ctrl, a `<position kp kv>` gear (kp (c - gear q) - kv gear qdot), a
`<velocity kv>` gear kv (c - gear qdot), all evaluated at the step's start as MuJoCo's Euler integrator does
(which does not make actuator damping implicit). The others (site, body or tendon transmissions, activation
dynamics) are refused off MuJoCo before the run (``actuator:native``, runner.compile.robots).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from backends.base import Backend
from runner.language.model import Scenario
from runner.language.robot_desc import ActuatorDesc, ModelDesc


@dataclass(frozen=True)
class _Actuator:
    """An MJCF actuator the scenario drives by name, and the world joint it acts on."""

    index: int  # in the model file's actuator order (MuJoCo's)
    desc: ActuatorDesc
    joint: int | None  # the world joint it drives (None: not a hinge or slide)


def _clamp(x: float, bounds: tuple[float, float] | None) -> float:
    return x if bounds is None else max(bounds[0], min(bounds[1], x))


class Actuators:
    """The actuators the scenario drives and their `ctrl` now, by `<robot>.<actuator>`."""

    def __init__(self, model: Scenario, robots: dict[str, ModelDesc], joint_index: dict[str, int]) -> None:
        self.known: dict[str, _Actuator] = {}
        for rname, desc in robots.items():
            for a, act in enumerate(desc.actuators):
                joint = joint_index.get(f"{rname}.{act.joint}") if act.joint is not None else None
                self.known[f"{rname}.{act.name}"] = _Actuator(a, act, joint)
        self.ctrl: dict[str, float | str] = {
            f"{rname}.{aname}": control.ctrl
            for rname, robot in model.robots.items()
            for aname, control in robot.actuators.items()
        }

    def __bool__(self) -> bool:
        return bool(self.ctrl)

    def set(self, actuator: str, ctrl: float | str) -> None:
        self.ctrl[actuator] = ctrl

    def drive_native(self, backend: Backend, number: Callable[[float | str], float]) -> None:
        """The engine runs the file's actuators: each one's `ctrl` now."""
        for name, ctrl in self.ctrl.items():
            value = number(ctrl)
            if math.isfinite(value):  # a NaN from the readings is the engine's failure, reported by the runner
                backend.set_control(self.known[name].index, value)

    def torques(
        self, positions: list[float], rates: list[float], number: Callable[[float | str], float]
    ) -> dict[int, float]:
        """Joint -> this step's torque (force) of the actuators on it, by MuJoCo's law (module docstring)."""
        out: dict[int, float] = {}
        for name, ctrl in self.ctrl.items():
            act = self.known[name]
            if act.joint is None:  # refused before the run on such an engine (actuator:native)
                continue
            d, k = act.desc, act.joint
            c = _clamp(number(ctrl), d.ctrlrange)
            force = d.gain * c + d.bias[0] + d.bias[1] * d.gear * positions[k] + d.bias[2] * d.gear * rates[k]
            out[k] = out.get(k, 0.0) + d.gear * _clamp(force, d.forcerange)
        return out
