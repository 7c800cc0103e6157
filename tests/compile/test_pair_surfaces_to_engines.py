"""A scenario's pair `surfaces:` followed from the YAML through compile to each engine's own contact
parameters, read back from the engine after the build: the mapping chain that a swapped `bounce` and `mu`
(positional Surface arguments, a pair table mixed up) would break without any trajectory test noticing at once.

Three bodies, three pairs that can touch (the two boxes are far apart, but every pair with a dynamic body is
given its surface): ground-a and ground-b have surfaces of their own, a-b the default. The values are
chosen so that every engine's combining rule has an exact per-body solution (DART: friction min(fa, fb)
with f = 0.8, 0.8, 0.25; restitution ra*rb with r = 0.5, 1.0, 0.2; PyBullet: both products, three pairs for
three bodies) and so that bounce and mu differ in every pair.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import pytest

from backends.base import Backend
from backends.errors import UnsupportedFeature
from backends.registry import create_backend, is_installed
from runner.compile.program import build_program
from runner.language.load import load_scenario
from tests.engines import ENGINES

SCENARIO = """\
schema_version: 1
scenario: pair-surfaces
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
surface: {bounce: 0.2, mu: 0.25}
surfaces:
  - {bodies: [ground, a], bounce: 0.5, mu: 0.8}
  - {bodies: [b, ground], bounce: 0.1, mu: 0.25}
bodies:
  ground: {plane: {}, motion: static}
  a: {box: [0.2, 0.2, 0.2], density: 500, pos: [0, 0, 0.1]}
  b: {box: [0.2, 0.2, 0.2], density: 500, pos: [3, 0, 0.1]}
"""
#: pair -> (bounce, mu) as the scenario asks
EXPECTED = {("ground", "a"): (0.5, 0.8), ("ground", "b"): (0.1, 0.25), ("a", "b"): (0.2, 0.25)}
Pair = tuple[str, str]
#: what each engine holds for a pair after its build: (restitution, friction) as the engine combines them
Reader = Callable[[Backend, Pair], tuple[float, float]]


def _pybullet(sim: Backend, pair: Pair) -> tuple[float, float]:
    """Per-body lateralFriction and restitution from getDynamicsInfo, combined as Bullet does (products,
    friction clamped at 10: backends/pybullet/_surfaces.py)."""
    import pybullet as p

    from backends.pybullet._surfaces import FRICTION_BLEND, FRICTION_CLAMP, RESTITUTION_BLEND

    info = []
    for name in pair:
        i = sim.world.body_index(name)
        dyn = p.getDynamicsInfo(sim._layout.uid[i], sim._layout.link[i], physicsClientId=sim._c)  # type: ignore[attr-defined]
        info.append((dyn[5], dyn[1]))  # restitution, lateral friction
    (ra, fa), (rb, fb) = info
    return RESTITUTION_BLEND.combine(ra, rb), min(FRICTION_BLEND.combine(fa, fb), FRICTION_CLAMP)


def _dart(sim: Backend, pair: Pair) -> tuple[float, float]:
    """Each shape's DynamicsAspect, combined by DART's rules (ContactSurface.cpp: min friction, product
    restitution)."""
    from backends.dart._surfaces import FRICTION_BLEND, RESTITUTION_BLEND

    values = []
    for name in pair:
        (aspect,) = sim._bodies[sim.world.body_index(name)].aspects  # type: ignore[attr-defined]
        values.append((aspect.getRestitutionCoeff(), aspect.getFrictionCoeff()))
    (ra, fa), (rb, fb) = values
    return RESTITUTION_BLEND.combine(ra, rb), FRICTION_BLEND.combine(fa, fb)


def _mujoco(sim: Backend, pair: Pair) -> tuple[float, float]:
    """The compiled model's explicit contact pair for the two geoms, else the geoms' own (equal) parameters:
    friction[0] is mu; the normal solref's damping term is -(1 + e)/h (backends/mujoco/_geoms.py)."""
    m = sim._m  # type: ignore[attr-defined]
    ga, gb = (m.geom(f"geom:{name}").id for name in pair)
    h = m.opt.timestep
    for k in range(m.npair):
        if {int(m.pair_geom1[k]), int(m.pair_geom2[k])} == {ga, gb}:
            return -m.pair_solref[k][1] * h - 1.0, float(m.pair_friction[k][0])
    assert m.geom_friction[ga][0] == m.geom_friction[gb][0] and m.geom_solref[ga][1] == m.geom_solref[gb][1]
    return -m.geom_solref[ga][1] * h - 1.0, float(m.geom_friction[ga][0])


def _ode(sim: Backend, pair: Pair) -> tuple[float, float]:
    """The OdeSurfaceParameters the collider gives each contact of the two bodies' surface classes."""
    scene, collider = sim._scene, sim._collider  # type: ignore[attr-defined]
    key = tuple(scene.surface_class[sim.world.body_index(name)] for name in pair)
    params = collider._params[key]
    return params.getBounce(), params.getMu()


def _drake(sim: Backend, pair: Pair) -> tuple[float, float]:
    """Each geometry's ``material/coulomb_friction`` in SceneGraph, combined as Drake combines them (the harmonic
    mean, backends/drake/_friction.py); Drake has no restitution (the scenario is refused with bounce: below)."""
    built = sim._built  # type: ignore[attr-defined]
    inspector = built.scene_graph.model_inspector()
    mus = []
    for name in pair:
        i = sim.world.body_index(name)
        gids = [g for g in inspector.GetAllGeometryIds() if built.geometry_body.get(g.get_value()) == i]
        values = {inspector.GetProximityProperties(g).GetProperty("material", "coulomb_friction").dynamic_friction()
                  for g in gids}  # fmt: skip
        assert len(values) == 1, (name, values)
        mus.append(values.pop())
    ma, mb = mus
    return 0.0, 2.0 * ma * mb / (ma + mb)


READERS: dict[str, Reader] = {"pybullet": _pybullet, "dart": _dart, "drake": _drake, "mujoco": _mujoco, "ode": _ode}
#: engines without restitution (capability contact:bounce): the scenario is refused naming it, and its bounce-free
#: copy is checked for mu alone
NO_BOUNCE = {"drake"}
#: relative: float64 engines hold the values to rounding of the per-body solve (1e-12 in log space, the
#: MuJoCo solref's product with h); ODE (panda3d) stores dReal in float32: 2^-24 = 6e-8 per value
REL = {"ode": 1e-6}


@pytest.mark.parametrize("engine", ENGINES)
def test_pair_surfaces_reach_the_engines_contact_parameters(engine: str, tmp_path: Path) -> None:
    if not is_installed(engine):
        pytest.skip(f"{engine} not installed")
    if engine not in READERS:
        pytest.fail(f"no reader of {engine}'s contact parameters here: add one to READERS")
    path = tmp_path / "pairs.yaml"
    path.write_text(SCENARIO)
    world = build_program(load_scenario(path)).world
    for (a, b), (bounce, mu) in EXPECTED.items():  # compile: the scenario's numbers, each in its field
        assert world.surface(a, b) == world.surface(b, a)
        assert (world.surface(a, b).bounce, world.surface(a, b).mu) == (bounce, mu), (a, b)
    rel = REL.get(engine, 1e-9)
    expected = EXPECTED
    if engine in NO_BOUNCE:
        with pytest.raises(UnsupportedFeature, match="contact:bounce"):
            create_backend(engine, world)
        path.write_text(SCENARIO.replace("bounce: 0.5", "bounce: 0").replace("bounce: 0.1", "bounce: 0")
                        .replace("bounce: 0.2", "bounce: 0"))  # fmt: skip
        world = build_program(load_scenario(path)).world
        expected = {pair: (0.0, mu) for pair, (_, mu) in EXPECTED.items()}
    with create_backend(engine, world) as sim:
        for pair, (bounce, mu) in expected.items():
            got_bounce, got_mu = READERS[engine](sim, pair)
            assert math.isclose(got_bounce, bounce, rel_tol=rel), f"{pair}: restitution {got_bounce}, not {bounce}"
            assert math.isclose(got_mu, mu, rel_tol=rel), f"{pair}: friction {got_mu}, not {mu}"
