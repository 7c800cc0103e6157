"""Armature at an impact: a free ball strikes a body held by a joint with armature, without gravity, and the
pair's momentum along the joint's coordinate (linear for a slider, angular about a hinge's axis) is conserved
with the armature counted as inertia of the coordinate, as MuJoCo's ``M_qq + a`` makes it (docs/semantics.md,
"Joint dynamics"). The contact's impulses are internal to the pair and the joint is world-fixed, so

    slider:  m_b v_b' + (m + a) v'     = m_b v_0
    hinge:   L_b'    + (I + a) omega'  = L_b0,   L_b = (m_b (p_b - anchor) x v_b + I_b w_b) . axis

whatever the contact's restitution, softness or position correction. Friction is 0 (the ball's spin I_b w_b is
counted all the same: Drake's contact sets the ball spinning at 0.099 rad/s, 1e-4 of L_b0).
An engine whose contact impulses see the joint without its armature conserves ``m`` (or ``I``) instead and
creates the armature's share of momentum from nothing.

DART's constraint solver uses the explicit projected articulated inertia, which its armature emulation (the
implicit damping term, backends/dart/_armature.py) does not reach; backends/dart/_impacts.py re-sizes each step's
impulse through ``M + A`` (exact for one frictionless contact, as here). Before it, the block ended at the common
speed of m_b and m (0.5 m/s: the counted momentum 1.5 instead of 1) and the rod at 1.358 rad/s, near the plastic
1.348 of I alone (counted angular momentum 0.663 instead of 0.5): what stopped five MJCF models and dm_control's
dog on DART in the robot survey (docs/backends/dart.md, "Joint dynamics").

Across the armatures users write (ARMATURE_RATIOS: 0.05 to 20 times the coordinate's own inertia) and with a
plastic and an elastic contact (BOUNCES, where the engine has restitution).

Tolerance: ODE is single precision; one step's rounding is at most 2^-23 of the momentum, so ``STEPS x 2^-23``
(3.6e-5 relative) bounds what the run can accumulate; the others are double precision and far inside it. An
ignored armature is off by ``a v'`` (a third of the momentum here), four orders above.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backends.registry import KNOWN_BACKENDS, get_backend, is_installed
from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from runner.sim.run import run_loaded

pytestmark = pytest.mark.slow
H, STEPS = 0.001, 300
TOLERANCE = STEPS * 2.0**-23
ENGINES = [
    n
    for n, e in KNOWN_BACKENDS.items()
    if not (e.hidden or e.opt_in)
    and is_installed(n)
    and "joint:armature" in {c.value for c in get_backend(n).capabilities}
]
CASES = {
    # the block on a slider along x; the ball comes along x and meets it head on
    "slider": (
        "  block: {box: [0.2, 0.2, 0.2], mass: 1, pos: [0, 0, 1]}\n"
        "  ball: {sphere: 0.05, mass: 1, pos: [-0.2, 0, 1], vel: [1, 0, 0]}\n",
        "  joint: {type: slider, bodies: [block, environment], axis: [1, 0, 0], dynamics: {armature: %r}}\n",
    ),
    # a 0.6 m rod on a vertical hinge at its end (I about the hinge 0.1208 kg m^2); the ball strikes it 0.5 m out
    "hinge": (
        "  block: {box: [0.6, 0.1, 0.1], mass: 1, pos: [0.3, 0, 1]}\n"
        "  ball: {sphere: 0.05, mass: 1, pos: [0.5, -0.2, 1], vel: [0, 1, 0]}\n",
        "  joint: {type: hinge, bodies: [block, environment], axis: [0, 0, 1], anchor: [0, 0, 1], "
        "dynamics: {armature: %r}}\n",
    ),
}
#: the armature against the coordinate's own inertia (the block's mass, the rod's 0.1208 kg m^2): a light rotor,
#: an equal one (the MJCF models' range: dm_control's cheetah 0.1 on links of 0.1-1) and one that dominates
#: (dog's tail: 1e5 times its links); with a plastic and an elastic contact
ARMATURE_RATIOS = (0.05, 1.0, 20.0)
BOUNCES = (0.0, 0.6)
COORDINATE_INERTIA = {"slider": 1.0, "hinge": (0.6**2 + 0.1**2) / 12 + 0.3**2}
ROD_INERTIA = (0.6**2 + 0.1**2) / 12 + 0.3**2
BALL_INERTIA = 0.4 * 0.05**2  # a 1 kg solid sphere of 0.05 m about its centre


def _momenta(tmp_path: Path, engine: str, case: str, ratio: float, bounce: float) -> tuple[float, float]:
    """(before, after): the pair's momentum along the joint's coordinate, the armature counted."""
    bodies, joint = CASES[case]
    armature = ratio * COORDINATE_INERTIA[case]
    joints = joint % armature
    path = tmp_path / "s.yaml"
    path.write_text(
        "schema_version: 1\nscenario: armature-impact\n"
        f"world: {{gravity: [0, 0, 0], dt: {H}, duration: {STEPS * H!r}}}\n"
        f"surface: {{mu: 0, bounce: {bounce!r}}}\n"
        f"bodies:\n{bodies}joints:\n{joints}"
    )
    result = run_loaded(load_scenario(path), engine, tmp_path / "out")
    assert result.status == "passed" and result.trace is not None, result.failure
    trace = read_trace(result.trace)
    ball, block = trace.bodies["ball"], trace.bodies["block"]
    if case == "slider":
        before = ball.vel[0][0]
        after = ball.vel[-1][0] + (1.0 + armature) * block.vel[-1][0]  # m = 1
        moved = block.vel[-1][0]
    else:
        arm0, arm = ball.pos[0] - (0, 0, 1), ball.pos[-1] - (0, 0, 1)
        before = float(np.cross(arm0, ball.vel[0])[2])
        spin = BALL_INERTIA * ball.angvel[-1][2]
        after = float(np.cross(arm, ball.vel[-1])[2]) + spin + (ROD_INERTIA + armature) * block.angvel[-1][2]
        moved = block.angvel[-1][2]
    # the ball did strike: the coordinate takes at least the plastic share of the momentum, 1 / (1 + 20) of it
    assert moved > 0.02, (engine, case, moved)
    return before, after


#: measured deviations beyond the bound, with their cause (not widened): PyBullet's armature is a rotor body
#: geared to the joint (backends/pybullet/_rotors.py), whose gear row Bullet solves with the contact's. On the
#: hinge, plastic, the pair's counted momentum is off by 2.5e-11 at armature 0 and by 3.2e-5, 3.8e-5, 3.3e-5
#: at 10, 20, 30 times the rod's inertia, the same with 1 or 100 Gauss-Seidel sweeps over the gears (ROTOR_SWEEPS);
#: the slider keeps it to 1e-8. Not examined further.
KNOWN_DEVIATIONS = {
    ("pybullet", "hinge", 20.0, 0.0): "PyBullet's geared rotor at an impact: 3.8e-5 of the momentum (bound 3.6e-5)",
}


def _bounces(engine: str) -> tuple[float, ...]:
    """Restitution where the engine has it (Drake refuses ``contact:bounce`` up front)."""
    declared = {c.value for c in get_backend(engine).capabilities}
    return BOUNCES if "contact:bounce" in declared else (0.0,)


@pytest.mark.parametrize(
    ("engine", "case", "ratio", "bounce"),
    [
        pytest.param(
            e, c, r, b,
            marks=[pytest.mark.xfail(strict=True, reason=KNOWN_DEVIATIONS[(e, c, r, b)])]
            if (e, c, r, b) in KNOWN_DEVIATIONS
            else [],
        )
        for e in ENGINES
        for c in sorted(CASES)
        for r in ARMATURE_RATIOS
        for b in _bounces(e)
    ],
)  # fmt: skip
def test_an_impact_sees_the_joints_armature(
    tmp_path: Path, engine: str, case: str, ratio: float, bounce: float
) -> None:
    before, after = _momenta(tmp_path, engine, case, ratio, bounce)
    assert abs(after - before) <= TOLERANCE * abs(before), (engine, case, before, after)
