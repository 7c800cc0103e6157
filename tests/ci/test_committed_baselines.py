"""The committed golden files: one per scenario x variant x backend for the top-level example scenarios, readable,
and naming what they hold. (Whether runs still match them is what `.ci/run` checks with `scenario check`.)"""

from __future__ import annotations

import pytest

from backends.errors import UnsupportedFeature
from backends.registry import check_capabilities, get_backend, is_installed, list_backends
from runner.ci.golden_read import read_golden
from runner.ci.regression import golden_path
from runner.compile.world import compile_world
from runner.language.load import load_all

from .conftest import ROOT, SCENARIOS

BASELINES = ROOT / "baselines"
CASES = [case for path in sorted(SCENARIOS.glob("*.yaml")) for case in load_all(path, None, True, ())]


def _runs(case: object, backend: str) -> bool:
    """Whether ``backend`` runs the hand-written example ``case`` (a case it refuses up front, as drake refuses
    `bounce`, has no golden file: `scenario baseline` records none)."""
    if not is_installed(backend):
        return True
    try:
        check_capabilities(get_backend(backend), compile_world(case.model, case.model.scenario))  # type: ignore[attr-defined]
    except UnsupportedFeature:
        return False
    return True


@pytest.mark.parametrize("backend", [e.name for e in list_backends() if not e.opt_in])
def test_every_example_case_has_a_golden_file(backend: str) -> None:
    for case in (c for c in CASES if _runs(c, backend)):
        path = golden_path(BASELINES, case, backend)
        golden = read_golden(path)
        header = golden.header
        assert (header["scenario"], header["variant"], header["backend"]) == (
            case.model.scenario, case.variant, backend
        ), path  # fmt: skip
        assert header["scenario_file"] == case.path.name and float(header["dt"]) == case.model.world.dt
        assert [v.name for v in golden.verdicts] == [a.name for a in case.model.assertions], path
        assert golden.header["status"] == "passed", path


def test_no_stray_golden_files() -> None:
    expected = {
        golden_path(BASELINES, c, e.name).name
        for c in CASES
        for e in list_backends()
        if not e.opt_in and _runs(c, e.name)
    }
    assert {p.name for p in BASELINES.glob("*.golden")} == expected
