"""The committed golden files: one per scenario x variant x backend for the top-level example scenarios, readable,
and naming what they hold. (Whether runs still match them is what `.ci/run` checks with `scenario check`.)"""

from __future__ import annotations

import pytest

from backends.registry import list_backends
from runner.ci.golden import read_golden
from runner.ci.regression import golden_path
from runner.language.load import load_all

from .conftest import ROOT, SCENARIOS

BASELINES = ROOT / "baselines"
CASES = [case for path in sorted(SCENARIOS.glob("*.yaml")) for case in load_all(path, None, True, ())]


@pytest.mark.parametrize("backend", [e.name for e in list_backends()])
def test_every_example_case_has_a_golden_file(backend: str) -> None:
    for case in CASES:
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
    expected = {golden_path(BASELINES, c, e.name).name for c in CASES for e in list_backends()}
    assert {p.name for p in BASELINES.glob("*.golden")} == expected
