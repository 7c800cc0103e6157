"""ODE refuses a jointed group whose masses or inertias span more than float32 resolves (backends/ode/_ranges.py).

The bound is float32's epsilon, 2^-23: below it a heavy body's terms of ODE's constraint matrix are under the
rounding of a light one's, and dm_control's dog aborted ODE (signal 6, a zero pivot) when its tail landed.
The corpus check (which files the rule refuses) is the survey's: these tests pin the rule on real files.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

pytest.importorskip("panda3d.ode")
pytest.importorskip("pybullet_data")
dm_control = pytest.importorskip("dm_control")

from backends.errors import UnsupportedFeature  # noqa: E402
from backends.ode import OdeBackend  # noqa: E402
from backends.ode._options import OdeOptions  # noqa: E402
from backends.ode._ranges import FLOAT32_EPS  # noqa: E402
from backends.types import CompiledWorld  # noqa: E402
from runner.compile.program import build_program  # noqa: E402
from runner.survey.cases import load_survey_scenario  # noqa: E402
from runner.survey.models import find_models  # noqa: E402

SUITE = Path(dm_control.__file__).parent / "suite"


def _engine_world(path: str) -> CompiledWorld:
    (model,) = find_models([path])
    return OdeBackend.engine_world(build_program(load_survey_scenario(model, 0.5)).world)


def _check(world: CompiledWorld) -> None:
    OdeBackend.check_world(world, OdeOptions())


def test_dog_is_refused_naming_its_tail_tip() -> None:
    """Ca_21: 5.97e-10 kg m^2 against the torso's 0.026 kg m^2, 2.3e-8 < 2^-23 = 1.19e-7."""
    with pytest.raises(UnsupportedFeature) as info:
        _check(_engine_world(str(SUITE / "dog.xml")))
    text = str(info.value)
    assert "`model.Ca_21` (and 1 more)" in text  # Ca_20: 1.35e-9 / 0.026 = 5.2e-8, the other below
    assert "2.3e-08 of `model.torso`'s 0.026" in text
    assert "backend `ode`" in text


def test_the_bound_is_float32_epsilon() -> None:
    """dog's tail tip raised to just above 2^-23 of the torso's inertia (and its neighbour Ca_20 with it) is
    accepted; just below, refused."""
    world = _engine_world(str(SUITE / "dog.xml"))
    largest = max(max(b.inertia) for b in world.bodies if b.name == "model.torso")

    def tail_at(ratio: float) -> CompiledWorld:
        floor = ratio * largest
        tail = ("model.Ca_20", "model.Ca_21")
        return replace(world, bodies=tuple(
            replace(b, inertia=(max(b.inertia[0], floor), max(b.inertia[1], floor), max(b.inertia[2], floor)))
            if b.name in tail else b for b in world.bodies))  # fmt: skip

    _check(tail_at(FLOAT32_EPS * 1.01))
    with pytest.raises(UnsupportedFeature):
        _check(tail_at(FLOAT32_EPS * 0.99))


def test_chain_light_bodies_and_held_bodies_are_left_out() -> None:
    """humanoid_CMU's thumb chain makes light bodies of 1e-3 of a 4.5e-6 ratio (the file's own smallest),
    below 2^-23: the mapping's own bodies, measured in backends/_kit/chains.py, so it runs. pusher's target and
    object (4e-10 and 1.3e-8 kg on sliders, held still: _held) are not compared either."""
    cmu = _engine_world(str(SUITE / "humanoid_CMU.xml"))
    light = cmu.chain_bodies
    assert "model.lthumb (after joint model.lthumbrz)" in light
    assert all(" (after joint " in name for name in light)  # chains.py's names: every one found is a light body
    assert len(light) == len(cmu.bodies) - len(build_program(load_survey_scenario(
        find_models([str(SUITE / "humanoid_CMU.xml")])[0], 0.5)).world.bodies)  # fmt: skip
    _check(cmu)
    _check(_engine_world("@pybullet_data/mjcf/pusher.xml"))


@pytest.mark.parametrize("name", ["manipulator.xml", "stacker.xml"])
def test_the_pinch_site_is_refused_now_that_ode_holds_mimics(name: str) -> None:
    """The "pinch site" (1e-12 kg m^2, welded to the hand) is 2.1e-9 of the upper arm's inertia: refused for
    `joint:mimic` before ODE had mimics, by this rule since (its docstring: lending it the hand's inertia and mass
    passed the rule, but ODE stayed at its zero pivot's edge)."""
    with pytest.raises(UnsupportedFeature) as info:
        _check(_engine_world(str(SUITE / name)))
    assert "Body `model.pinch site`" in str(info.value) and "2.1e-09 of `model.upper_arm`'s" in str(info.value)
