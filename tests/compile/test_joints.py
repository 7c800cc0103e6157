"""Joint limits with a stated zero (a compile-time conversion to the backends' zero, the start pose), and stops
with bounce or softness (in the language and the contract; refused where no engine maps them yet)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from backends.errors import UnsupportedFeature
from backends.registry import get_backend, is_installed
from backends.types import UNMAPPED_CAPABILITIES, Capability
from runner.compile.program import build_program
from runner.language.load import load_scenario
from runner.sim.run import run_loaded
from tests.engines import ENGINES

ROLL = 20.0  # degrees: the bob's start orientation, a rotation about +y (Panda3D's roll axis)
HI = 0.6  # rad, the high stop from the absolute zero

# Conformance 5's hinge (a 1 kg bob, r 0.05, 0.5 m out along +x of an anchor, axis +y: a positive angle turns
# +x towards -z), started rolled by 20 degrees: with `zero: absolute` its angle is measured from the
# orientation equal to the world's, so it starts at 20 degrees = 0.349 rad, and the stop at 0.6 rad absolute is
# 0.6 - 0.349 = 0.251 rad from the start. Gravity pulls it onto that stop.
HINGE = f"""\
schema_version: 1
scenario: zero
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 2.0}}
bodies:
  bob: {{sphere: 0.05, mass: 1, pos: [5.5, 0, 1], hpr: [0, 0, {ROLL}]}}
joints:
  hinge:
    type: hinge
    bodies: [bob, environment]
    axis: [0, 1, 0]
    anchor: [5, 0, 1]
    limits: {{lo: -0.5, hi: {HI}, zero: absolute}}
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "j.yaml"
    path.write_text(text)
    return path


def test_an_absolute_hinge_zero_is_the_orientation_equal_to_the_others(tmp_path: Path) -> None:
    program = build_program(load_scenario(write(tmp_path, HINGE)))
    start = math.radians(ROLL)
    joint = program.world.joints[0]
    assert joint.lo == pytest.approx(-0.5 - start, abs=1e-12) and joint.hi == pytest.approx(HI - start, abs=1e-12)
    assert program.joint_zeros == {"hinge": pytest.approx(start, abs=1e-12)}


def test_an_absolute_slider_zero_is_the_anchor_or_the_other_bodys_origin(tmp_path: Path) -> None:
    text = """\
schema_version: 1
scenario: zero
world: {dt: 0.01, duration: 1}
bodies:
  rail: {box: [4, 0.1, 0.1], motion: static, pos: [1, 0, 0]}
  car: {box: [0.2, 0.2, 0.2], mass: 1, pos: [1.2, 0.5, 0]}
joints:
  s1: {type: slider, bodies: [car, environment], axis: [2, 0, 0], limits: {lo: 1.0, hi: 1.5, zero: absolute}}
  s2: {type: slider, bodies: [car, environment], axis: [1, 0, 0], anchor: [0.7, 0, 0],
       limits: {lo: 0, hi: 1, zero: absolute}}
  s3: {type: slider, bodies: [car, environment], axis: [1, 0, 0], limits: [-0.1, 0.1]}
"""
    program = build_program(load_scenario(write(tmp_path, text)))
    s1, s2, s3 = program.world.joints
    assert (s1.lo, s1.hi) == pytest.approx((1.0 - 1.2, 1.5 - 1.2))  # from the world origin along the unit axis
    assert (s2.lo, s2.hi) == pytest.approx((0 - 0.5, 1 - 0.5))  # from the anchor
    assert (s3.lo, s3.hi) == (-0.1, 0.1) and "s3" not in program.joint_zeros  # zero: start, as before


@pytest.mark.parametrize("engine", ENGINES)
def test_a_hinge_rests_on_its_absolute_stop_and_reads_from_that_zero(tmp_path: Path, engine: str) -> None:
    if not is_installed(engine):
        pytest.skip(f"{engine} not installed")
    rest = HI - math.radians(ROLL)  # the rotation from the start pose at rest
    # tolerances: conformance 5's, whose derivation holds here (ODE's CFM-softened stop and MuJoCo's impedance
    # give 2.2e-6 and 9.5e-6 rad under this bob's 4.75 N m; the bob's position is 0.5 m times that)
    text = HINGE + f"""\
assertions:
  - {{name: starts-at-its-absolute-angle, at: 0, value: hinge.position, near: {math.radians(ROLL)!r}, tol: 1e-9}}
  - {{name: rests-at-the-absolute-stop, at: end, value: hinge.position, near: {HI}, tol: {{default: 1e-6, ode: 1e-5,
      mujoco: 2e-5}}}}
  - {{name: bob-where-the-stop-puts-it, at: end, value: bob.pos.z, near: 1 - 0.5*sin({rest!r}), tol: 1e-5}}
"""
    result = run_loaded(load_scenario(write(tmp_path, text)), engine, None)
    assert result.passed, [(v.name, v.measured, v.expected) for v in result.verdicts]


@pytest.mark.parametrize("limits,capability", [
    ("{lo: -1, hi: 1, bounce: 0.5}", Capability.JOINT_STOP_BOUNCE),
    ("{lo: -1, hi: 1, stiffness: 1000, damping: 10}", Capability.JOINT_STOP_SOFTNESS),
])  # fmt: skip
@pytest.mark.parametrize("engine", [*ENGINES, "fake"])
def test_stop_bounce_and_softness_are_refused_up_front_until_an_engine_maps_them(
    tmp_path: Path, engine: str, limits: str, capability: Capability
) -> None:
    if not is_installed(engine):
        pytest.skip(f"{engine} not installed")
    if capability in get_backend(engine).capabilities:  # ODE declares both: its joints have their own stops
        pytest.skip(f"{engine} maps {capability.value}")
    text = HINGE.replace(f"{{lo: -0.5, hi: {HI}, zero: absolute}}", limits).replace("type: hinge", "type: slider")
    program = build_program(load_scenario(write(tmp_path, text)))
    joint = program.world.joints[0]
    assert joint.stop_bounce == (0.5 if "bounce" in limits else 0.0)
    assert joint.stop_stiffness == (1000 if "stiffness" in limits else None)
    assert capability in program.world.required_capabilities() and capability in UNMAPPED_CAPABILITIES
    with pytest.raises(UnsupportedFeature, match=f"needs .*{capability.value}.*which backend `{engine}` does not"):
        run_loaded(load_scenario(write(tmp_path, text)), engine, None)
