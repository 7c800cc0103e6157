"""The contract's sensing reads: joint reactions (capability ``joint:reaction``, Backend.joint_reactions)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from backends.base import Backend
from backends.types import Capability, JointKind, JointSpec

from . import worlds as w
from .contract_motion import _two_boxes
from .tolerances import tol
from .worlds import ZERO, make_backend, require

_RIGID_ODE = {"ode": {"cfm": 1e-8}}  # see the test's docstring


@pytest.mark.parametrize("substeps", [1, 4])
@pytest.mark.parametrize("first", ["b", "a"], ids=["child-first", "parent-first"])
def test_joint_reaction_is_the_wrench_on_the_first_body(
    backend_name: str, backend_cls: type[Backend], first: str, substeps: int
) -> None:
    """Box b (4 kg) glued on top of box a (8 kg) in zero gravity; 120 N up on a's centre for every step: both
    accelerate at 120/12 = 10 m/s^2, so the glue pulls b up with m_b a = 40 N and a down with -40 N, along the
    line through both centres (no torque about the first body's centre). Which end is the joint's first body
    decides the sign; an engine's tree may hang the joint from either end (the adapters' sign). Tolerance: the
    force is a constraint's, relative tol("motor_force") (the rows' softness: MuJoCo's impedance gap, as for a
    motor's force; a float64 engine with a rigid weld gives it to rounding). ODE runs with CFM 1e-8: at the
    lab's CFM 1e-5 ODE's own joint feedback under-reads a joint that accelerates its bodies (measured: 39.89 N
    on the first step, then 8.07 N on every later one while both boxes do accelerate at 10 m/s^2; 8.18 N at
    ERP 0.5; quickstep jumps between -11 and 16 N; exactly 40.0 N at CFM 1e-8; docs/backends/ode.md "Joint
    reactions"), which no mapping of the feedback can undo."""
    for cap in (Capability.JOINT_FIXED, Capability.JOINT_BETWEEN_BODIES, Capability.JOINT_REACTION):
        require(backend_cls, cap)
    other = "a" if first == "b" else "b"
    joint = JointSpec("glue", JointKind.FIXED, first, other)
    world = replace(_two_boxes(joint), substeps=substeps, reaction_joints=("glue",), backend_options=_RIGID_ODE)
    expected = 40.0 if first == "b" else -40.0
    rel = tol("motor_force", backend_name)
    with make_backend(backend_name, world) as sim:
        assert sim.joint_reactions() == pytest.approx(np.zeros((1, 6)))  # nothing before the first step
        for k in range(1, 11):
            sim.apply_force(0, (0.0, 0.0, 120.0), ZERO)
            sim.step()
            wrench = sim.joint_reactions()
            assert wrench.shape == (1, 6)
            assert wrench[0, 2] == pytest.approx(expected, rel=rel), f"step {k}"
            assert np.abs(wrench[0, [0, 1, 3, 4, 5]]).max() <= rel * 40.0, f"step {k}: {wrench}"


def test_watching_a_joint_reaction_changes_nothing_in_the_motion(
    backend_name: str, backend_cls: type[Backend]
) -> None:
    """A sensor only reads: a swinging pendulum with and without `reaction_joints` moves to the same bits."""
    for cap in (Capability.JOINT_HINGE, Capability.JOINT_REACTION):
        require(backend_cls, cap)
    world = w.offset_hinge()
    rows = []
    for watched in ((), (world.joints[0].name,)):
        with make_backend(backend_name, replace(world, reaction_joints=watched)) as sim:
            for _ in range(50):
                sim.step()
            rows.append(sim.body_states().rows().copy())
    assert np.array_equal(rows[0], rows[1])
