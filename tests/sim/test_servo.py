"""The position servo's law (runner.sim.servo) on the pure-Python backend, whose velocity motor is exact: the
error falls by 1 - gain dt per step while unsaturated, and by at most fmax dt / m per step when saturated."""

from __future__ import annotations

import pytest

from backends.fake import FakeBackend
from backends.types import BodySpec, CompiledWorld, JointKind, JointSpec, Motion, Motor, Shape, ShapeKind
from runner.sim.servo import Servos, ServoSpec


def _world(dt: float) -> CompiledWorld:
    box = BodySpec(
        "cart", Motion.DYNAMIC, Shape(ShapeKind.BOX, size=(1, 1, 1)), 2.0, (1, 1, 1), (0, 0, 0), (1, 0, 0, 0)
    )
    slider = JointSpec("rail", JointKind.SLIDER, "cart", None, axis=(1.0, 0.0, 0.0), motor=Motor(0.0, 0.0))
    return CompiledWorld("servo", (0.0, 0.0, 0.0), dt, 1, 1.0, (box,), (slider,))


class _NoNames:
    def value(self, name: str) -> float:
        raise KeyError(name)

    def call(self, func: str, args: object) -> float:
        raise KeyError(func)


@pytest.mark.parametrize("gain", [5.0, 20.0, 100.0])
def test_unsaturated_error_falls_geometrically(gain: float) -> None:
    dt, target = 0.01, 0.3
    backend = FakeBackend(_world(dt))
    servos = Servos((ServoSpec("rail", target, gain, 1e6, None),), {"rail": 0})
    position = 0.0
    for n in range(1, 60):
        servos.drive(backend, [position], _NoNames())
        backend.step()
        position = float(backend.joint_states().position[0])
        assert target - position == pytest.approx(target * (1 - gain * dt) ** n, abs=1e-12)


def test_saturated_servo_is_bounded_by_fmax() -> None:
    """fmax 1 N on 2 kg: the rate grows by at most fmax/m dt = 0.005 m/s per step."""
    dt = 0.01
    backend = FakeBackend(_world(dt))
    servos = Servos((ServoSpec("rail", 10.0, 50.0, 1.0, None),), {"rail": 0})
    position = 0.0
    for n in range(1, 20):
        servos.drive(backend, [position], _NoNames())
        backend.step()
        position = float(backend.joint_states().position[0])
        assert float(backend.joint_states().velocity[0]) == pytest.approx(n * 1.0 / 2.0 * dt, rel=1e-12)


def test_vmax_caps_the_commanded_rate() -> None:
    dt = 0.01
    backend = FakeBackend(_world(dt))
    servos = Servos((ServoSpec("rail", 10.0, 50.0, 1e6, 0.2),), {"rail": 0})
    servos.drive(backend, [0.0], _NoNames())
    backend.step()
    assert float(backend.joint_states().velocity[0]) == pytest.approx(0.2, rel=1e-12)
