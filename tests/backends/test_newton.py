"""The Newton adapter's own mapping (docs/backends/newton.md): the mean-rule surfaces (engine-free), the options
refused up front, and ODE's velocity motor built from a clamped joint force."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from backends.errors import UnsupportedFeature
from backends.newton._surfaces import solve, solve_means
from backends.registry import create_backend, is_installed
from backends.testing import worlds as w
from backends.types import PairSurface, Surface


def test_mean_rule_gives_every_pair_its_mu_and_bounce() -> None:
    """A cycle of three pairs (an odd cycle: one solution) solved so that each contact's mean of its two bodies'
    values is the pair's, to rounding."""
    a = w.box("a", (0.2, 0.2, 0.2), (0.0, 0.0, 0.1))
    b = w.box("b", (0.2, 0.2, 0.2), (0.0, 1.0, 0.1))
    pairs = (PairSurface("ground", "a", Surface(mu=0.8, bounce=0.3)),
             PairSurface("a", "b", Surface(mu=0.5, bounce=0.2)),
             PairSurface("b", "ground", Surface(mu=0.6, bounce=0.1)))  # fmt: skip
    world = w.world("pairs", [w.ground(), a, b], pairs=pairs)
    got = solve(world)
    for i, j, mu, e in ((0, 1, 0.8, 0.3), (1, 2, 0.5, 0.2), (0, 2, 0.6, 0.1)):
        assert (got.mu[i] + got.mu[j]) / 2 == pytest.approx(mu, abs=1e-12)
        assert (got.restitution[i] + got.restitution[j]) / 2 == pytest.approx(e, abs=1e-12)


def test_a_pair_the_mean_cannot_give_is_refused_naming_it() -> None:
    """ground-a 0.8, ground-b 0.25, a-b 0.5: b would need mu -0.05."""
    with pytest.raises(UnsupportedFeature, match="the pair `b`-`ground` cannot get its value"):
        solve_means(3, {(0, 1): 1.6, (0, 2): 0.5, (1, 2): 1.0}, ["ground", "a", "b"], "friction `mu`",
                    hi=math.inf, fallback=1.0, declared=frozenset({("b", "ground")}))  # fmt: skip


needs_newton = pytest.mark.skipif(not is_installed("newton"), reason="engine not installed: newton")


@needs_newton
def test_featherstone_refuses_bounce_and_kinematic_bodies_up_front() -> None:
    bouncy = replace(w.bouncing_sphere(0.5, 0.1), backend_options={"newton": {"solver": "featherstone"}})
    with pytest.raises(UnsupportedFeature, match="featherstone.*contact:bounce"):
        create_backend("newton", bouncy)
    platform = replace(w.kinematic_platform(), backend_options={"newton": {"solver": "featherstone"}})
    with pytest.raises(UnsupportedFeature, match="featherstone.*motion:kinematic"):
        create_backend("newton", platform)


@needs_newton
@pytest.mark.parametrize("n", [5, 6])
def test_a_resting_column_over_five_bodies_is_refused(n: int) -> None:
    """n boxes of 0.1 m resting one above the other: XPBD is measured to hold 5 (conformance 16: the top 12 mm
    low), not 10 (73 mm) nor 20 (the energy watchdog stops the run), so 6 and more are refused up front; a
    column dropped onto itself is not (the contract suite's busy world, 7 boxes)."""
    boxes = [w.box(f"b{k}", (0.1, 0.1, 0.1), (0.0, 0.0, 0.05 + 0.1 * k)) for k in range(n)]
    world = w.world("column", [w.ground(), *boxes])
    if n <= 5:
        create_backend("newton", world).close()
    else:
        with pytest.raises(UnsupportedFeature, match="resting column of 6 bodies; Newton's XPBD holds at most 5"):
            create_backend("newton", world)


@needs_newton
@pytest.mark.parametrize("solver", ["xpbd", "featherstone"])
def test_velocity_motor_is_odes_on_both_solvers(solver: str) -> None:
    """The lab door (400 kg, fmax 100 N, target 0.3 m/s, dt 0.04): ODE's v = min(0.3, 0.25 t) at every step,
    the motor force 100 N until the target is reached (float32 velocities: 1e-6 relative)."""
    world = replace(w.lab_door(), backend_options={"newton": {"solver": solver}})
    with create_backend("newton", world) as sim:
        for k in range(1, 36):
            sim.step()
            js = sim.joint_states()
            assert js.velocity[0] == pytest.approx(min(0.3, 0.01 * k), rel=1e-6), f"step {k}"
            if k < 30:
                assert js.motor_force[0] == pytest.approx(100.0, rel=1e-6)
