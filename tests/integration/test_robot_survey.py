"""The robot survey over real models nobody on the project wrote (issue 28's acceptance): pybullet's bundled
data (its URDFs and MJCFs; the 1,000 generated objects of `random_urdfs/` left out) and dm_control's suite,
each unmodified on a ground plane under gravity (`scenario robots survey`, docs/robots.md "The survey"),
on every installed engine.

The target, per engine: at least 90 % of the models run to the end; every other cell is refused before
the run with what is missing named; none crashes (exit 70, a signal) and none fails at t = 0. The issue
states it over the whole survey (pybullet_data's URDFs and MJCFs and dm_control's suite, 140 models):
`test_at_least_90_percent_of_the_whole_survey_run_on_each_engine`; each corpus's share is held apart too
(the MJCF corpus is where the engines other than MuJoCo miss: fluid forces, an acting tendon, a coupling
of three joints have no counterpart there).

Cost: the survey's cases are loading (meshes and their hulls) and building the world more than stepping,
so ``SECONDS`` of simulated time (0.5 s, 250 steps at the survey's dt = 2 ms) is enough for the energy
watchdog to see the landing (the models start 1 cm above the ground) and little of the cost. Measured on a
2-core machine shared with other work, ``-j 2``: 8.5 min for the URDF corpus (95 models x 4 engines); the
whole survey (140 models) took 8.5 min on its own in one process, so CI pays ~10 min for both. The table is
written to the test's temporary folder (and printed on failure).
"""

from __future__ import annotations

from pathlib import Path

import dm_control  # type: ignore[import-untyped]  # the `dev` extra: its suite of MJCF models
import pytest

from backends.registry import KNOWN_BACKENDS, is_installed
from runner.survey.models import find_models
from runner.survey.run import run_survey
from runner.survey.table import CRASHED, FAILED, RAN, REFUSED, Survey, markdown

pytestmark = pytest.mark.slow
SECONDS = 0.5
TARGET = 0.90
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in) and is_installed(n)]
SUITE = str(Path(dm_control.__file__).parent / "suite")
CORPORA = {
    "urdf": (["@pybullet_data"], ["random_urdfs/*", "*.xml"]),
    "mjcf": (["@pybullet_data/mjcf", SUITE], []),
}


#: each corpus's survey, run once per test session (the per-corpus and the whole-survey tests share them)
_SURVEYED: dict[str, Survey] = {}


def _surveyed(corpus: str, tmp_path_factory: pytest.TempPathFactory) -> Survey:
    if corpus not in _SURVEYED:
        paths, exclude = CORPORA[corpus]
        models = find_models(paths, exclude)
        assert len(models) >= (90 if corpus == "urdf" else 40)  # the corpus is there (pybullet_data, dm_control)
        done = run_survey(models, ENGINES, SECONDS, jobs=2)
        (tmp_path_factory.mktemp("survey") / f"{corpus}.md").write_text(markdown(done))
        _SURVEYED[corpus] = done
    return _SURVEYED[corpus]


@pytest.fixture(scope="module", params=sorted(CORPORA))
def survey(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Survey:
    return _surveyed(str(request.param), tmp_path_factory)


#: Engines known to run under 90 % of the MJCF corpus (45 files, 0.5 s). MuJoCo runs all 45 since MJCF's legacy
#: dialect is upgraded before MuJoCo's compiler reads a file (runner.language.mjcf_legacy). Measured: MuJoCo 45,
#: Drake 41 (91 %), DART 41 (since its constraint impulses see the armature, backends/dart/_impacts.py; 35
#: before), PyBullet 39, ODE 37; no other engine can reach 41: fish, ball_in_cup and quadruped need an acting
#: tendon or a coupling of three joints, striker a ball joint's dynamics (refused up front by name); the rest are
#: refused (float32 ranges on ODE: dog, thrower, manipulator, stacker) or stopped by the energy watchdog
#: (docs/robots.md, "The survey"). Each engine here is an expected miss until it reaches the target; reaching it
#: fails the test, so that this list goes.
MJCF_BELOW_TARGET = frozenset(ENGINES) - {"mujoco", "drake", "dart"}
#: Engines known to run under 90 % of the URDF corpus: none. Drake was (51 of 95, 40 refused for `shape:convex`)
#: until issue 32 mapped convex hulls: measured 91 of 95 since (docs/robots.md, "The survey").
URDF_BELOW_TARGET: frozenset[str] = frozenset()


#: Engines known to run under 90 % of the whole survey (140 models: 95 URDF, 45 MJCF; 0.5 s; 126 is 90 %).
#: Measured, ran (URDF + MJCF): MuJoCo 136 (91 + 45), Drake 132 (91 + 41), DART 131 (90 + 41; 125 before its
#: constraint impulses saw the armature, backends/dart/_impacts.py), PyBullet 130 (91 + 39) and ODE 127 (90 + 37;
#: 123 before its mesh pairs kept distinct contacts (laikago's two URDFs), its damping became an implicit row
#: (ant) and it held `<mimic>` by a force pair solved each step (franka_panda)): every engine meets it
#: (docs/robots.md, "The survey"). An engine that falls below is listed here as an expected miss, with its cause.
WHOLE_BELOW_TARGET: frozenset[str] = frozenset()


@pytest.mark.parametrize("engine", ENGINES)
def test_at_least_90_percent_of_the_whole_survey_run_on_each_engine(
    engine: str, tmp_path_factory: pytest.TempPathFactory
) -> None:
    surveys = [_surveyed(corpus, tmp_path_factory) for corpus in sorted(CORPORA)]
    ran = sum(s.totals(engine)[RAN] for s in surveys)
    models = sum(sum(s.totals(engine).values()) for s in surveys)
    met = ran >= TARGET * models
    if engine in WHOLE_BELOW_TARGET:
        assert not met, f"{engine} runs {ran} of {models} models: drop it from WHOLE_BELOW_TARGET"
        pytest.xfail(f"issue 28 open: {engine} runs {ran} of {models} models (WHOLE_BELOW_TARGET)")
    assert met, f"{engine} runs {ran} of {models} models\n" + "\n".join(markdown(s) for s in surveys)


@pytest.mark.parametrize("engine", ENGINES)
def test_at_least_90_percent_run_on_each_engine(survey: Survey, engine: str, request: pytest.FixtureRequest) -> None:
    counts = survey.totals(engine)
    met = counts[RAN] >= TARGET * sum(counts.values())
    if request.node.callspec.params["survey"] == "mjcf" and engine in MJCF_BELOW_TARGET:
        ran = f"{engine} runs {counts[RAN]} of {sum(counts.values())} MJCF models"
        assert not met, f"{ran}: drop it from MJCF_BELOW_TARGET"
        pytest.xfail(f"issue 28 open: {ran} (MJCF_BELOW_TARGET)")
    if request.node.callspec.params["survey"] == "urdf" and engine in URDF_BELOW_TARGET:
        ran = f"{engine} runs {counts[RAN]} of {sum(counts.values())} URDF models"
        assert not met, f"{ran}: drop it from URDF_BELOW_TARGET"
        pytest.xfail(f"{ran} (URDF_BELOW_TARGET)")
    assert met, f"{engine}: {counts}\n{markdown(survey)}"


@pytest.mark.parametrize("engine", ENGINES)
def test_nothing_crashes_or_fails_at_the_start(survey: Survey, engine: str) -> None:
    bad = {
        label: cells[engine]
        for label, cells in survey.rows.items()
        if cells[engine].kind == CRASHED or (cells[engine].kind == FAILED and cells[engine].text.startswith("t = 0 "))
    }
    assert not bad, f"{engine}: {bad}"


@pytest.mark.parametrize("engine", ENGINES)
def test_every_refusal_names_what_is_missing(survey: Survey, engine: str) -> None:
    """A refusal is the language's or the engine's message (exit 2), located and naming the feature."""
    refused = [(label, cells[engine].text) for label, cells in survey.rows.items() if cells[engine].kind == REFUSED]
    assert all(len(text) > 20 for _, text in refused), refused
