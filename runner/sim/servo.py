"""The position servo, ODE style, engine-neutral: a velocity motor commanded every step.

Before each step, for every servo joint: ``e = target - position`` (the joint's reading after the last
step), ``vel = clamp(gain * e, -vmax, vmax)``, and ``set_motor(joint, vel, fmax)``, the way ODE users
write a position servo (dParamVel = gain x error, dParamFMax = fmax). While the motor is not saturated the
engine holds the commanded rate exactly, so the error falls geometrically, ``e_{k+1} = (1 - gain dt) e_k``:
it converges without overshoot for ``gain dt <= 1`` (the loader refuses more) and reaches a fraction
``(1 - gain dt)^n`` of its start after n steps (docs/semantics.md, "Position servo"). The servo is the
runner's, so every engine gets the same commands; an adapter only needs ``set_motor``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from backends.base import Backend
from backends.types import NO_DYNAMICS, CompiledWorld
from runner.compile.joints import capped
from runner.language.expressions import Expression, Resolver, compile_expression
from runner.language.model import Scenario


@dataclass(frozen=True)
class ServoSpec:
    """A robot joint's position servo: target (a number or an expression), gain, fmax and vmax."""

    joint: str  # `<robot>.<joint>`
    target: float | Expression
    gain: float
    fmax: float
    vmax: float | None


def servo_specs(model: Scenario) -> tuple[ServoSpec, ...]:
    out = []
    for rname, robot in model.robots.items():
        for jname, joint in robot.joints.items():
            s = joint.servo
            if s is not None:
                target = float(s.target) if isinstance(s.target, float | int) else compile_expression(s.target)
                out.append(ServoSpec(f"{rname}.{jname}", target, s.gain, s.fmax, s.vmax))
    return tuple(out)


class Servos:
    """Commands every servo's motor from the latest joint readings (``positions``, world joint order)."""

    def __init__(
        self, specs: tuple[ServoSpec, ...], joint_index: dict[str, int], world: CompiledWorld | None = None
    ) -> None:
        self.specs = [(joint_index[s.joint], s) for s in specs]
        # each joint's effort and velocity limits cap the commands (docs/semantics.md, "Joint dynamics")
        self.dynamics = {j: world.joints[j].dynamics if world else NO_DYNAMICS for j, _ in self.specs}
        #: per servo, what does not change between steps: (joint, gain, vmax, the joint's velocity limit, fmax
        #: within its effort limit): the same operations as ``capped``, in its order, without its per-step calls
        self._fixed = [(j, s.gain, s.vmax, self.dynamics[j].velocity, capped(0.0, s.fmax, self.dynamics[j])[1])
                       for j, s in self.specs]  # fmt: skip
        self._joints = tuple(j for j, _ in self.specs)
        self._fmaxes = [fixed[4] for fixed in self._fixed]
        #: the constant targets in place (0 where an expression's goes), and the expressions with their places;
        #: with no expression, the template is every target (read once, not every step)
        self._template = [s.target if isinstance(s.target, float) else 0.0 for _, s in self.specs]
        self._read = [(k, s.target) for k, (_, s) in enumerate(self.specs) if not isinstance(s.target, float)]

    def __bool__(self) -> bool:
        return bool(self.specs)

    def targets(self, resolver: Resolver) -> list[float]:
        """Every servo's target now, in ``specs`` order (an expression target is read every step)."""
        if not self._read:
            return self._template
        out = self._template.copy()
        for k, expression in self._read:
            out[k] = float(expression.number(resolver))
        return out

    def drive(self, backend: Backend, positions: list[float], resolver: Resolver) -> None:
        """Every servo's motor command, in one ``set_motors`` call (one engine call where the engine has one;
        the same commands as one ``set_motor`` per joint)."""
        vels = []
        isfinite = math.isfinite
        for (j, gain, vmax, limit, _), target in zip(self._fixed, self.targets(resolver), strict=True):
            vel = gain * (target - positions[j])
            if vmax is not None:
                vel = max(-vmax, min(vmax, vel))
            if limit is not None and isfinite(vel):  # a non-finite rate is dropped below, not clamped
                vel = max(-limit, min(limit, vel))
            vels.append(vel)
        if all(map(isfinite, vels)):
            backend.set_motors(self._joints, vels, self._fmaxes)
            return
        # a NaN reading is the engine's failure, which the runner reports itself: that joint gets no command
        kept = [k for k, vel in enumerate(vels) if isfinite(vel)]
        backend.set_motors(tuple(self._joints[k] for k in kept), [vels[k] for k in kept],
                           [self._fmaxes[k] for k in kept])  # fmt: skip
