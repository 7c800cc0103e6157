"""The conformance suite's files: one scenario per semantic, analytic expectations, reasoned tolerances."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from backends.registry import KNOWN_BACKENDS
from runner.conformance import DEFAULT_SUITE, discover
from runner.conformance.worker import run_case
from runner.language import model_assertions as A
from runner.language.load import load_scenario, variant_names

SCHEMA_LINE = "# yaml-language-server: $schema=../../runner/schema/scenario.schema.json"
FILES = sorted(DEFAULT_SUITE.glob("*.yaml"))


def test_one_scenario_per_semantic_of_the_issue() -> None:
    """Issue 6 lists 12 semantics, issue 17 adds 13 (isotropic friction), 14 and 15 (energy of a tumbling
    body and of a pendulum), 16 (stacks of 5-30) and 17 (restitution over mass, size, dt and e), issue 29
    18 (held forces), 19 (joint reactions), 20 (a body's energy, momentum and body-frame spin) and 21 (named
    frames on links) and 22 (joint commands); the files are numbered after them (10 has three parts: a, b, c)."""
    numbers = {int(re.match(r"(\d+)", f.name).group(1)) for f in FILES}
    assert numbers == set(range(1, 23))


@pytest.mark.parametrize("path", FILES, ids=[f.stem for f in FILES])
def test_file_header_gives_schema_and_derivation(path) -> None:  # noqa: ANN001 - a Path
    lines = path.read_text().splitlines()
    assert lines[0] == SCHEMA_LINE
    header = [line for line in lines[1:] if line.startswith("#")]
    assert sum(len(line) > 40 for line in header) >= 2, "a derivation of the expected values in the header comment"
    assert "=" in " ".join(header), "the derivation states the formula"


@pytest.mark.parametrize("path", FILES, ids=[f.stem for f in FILES])
def test_every_per_backend_tolerance_names_its_measured_reason(path) -> None:  # noqa: ANN001 - a Path
    for variant in variant_names(path):
        model = load_scenario(path, None if variant == "base" else variant).model
        assert model.description, "the semantic, shown in the matrix"
        for a in model.assertions:
            tol = getattr(a, "tol", None)
            if not isinstance(tol, dict):
                continue
            for backend in set(tol) - {"default"}:
                assert backend in KNOWN_BACKENDS, f"{a.name}: unknown backend {backend}"
                assert a.description and f"{backend}:" in a.description, f"{a.name}: no reason given for {backend}"
                assert "measured" in a.description, f"{a.name}: the reason gives no measured figure"


def test_numeric_checks_compare_with_a_stated_value() -> None:
    """Every value/extremum check has an expected value and a tolerance (no bare min/max bounds only)."""
    for case in discover(DEFAULT_SUITE):
        model = load_scenario(case.path, case.variant).model
        for a in model.assertions:
            if isinstance(a, A.MaxAssertion | A.MinAssertion):
                assert a.near is not None
            if isinstance(a, A.ValueAssertion):
                assert a.near is not None, f"{case.id}: {a.name} has no analytic value"


def test_discover_lists_every_variant_with_its_checks() -> None:
    cases = discover(DEFAULT_SUITE)
    ids = [c.id for c in cases]
    assert len(ids) == len(set(ids))
    assert "08_friction/launched" in ids and "11_collision_events/behind" in ids and "01_free_fall" in ids
    assert all(c.checks for c in cases)
    free_fall = next(c for c in cases if c.id == "01_free_fall")
    height = next(ch for ch in free_fall.checks if ch.name == "height-at-end")
    assert height.measure == "ball.pos.z at end" and height.expected.startswith("param.z0 - g*dt*dt")
    # float32 rounding is in the tolerance (docs/semantics.md, Rounding), not a known limit
    assert height.tolerance == {"default": "1e-9 + (round(time/dt) + 1)*eps*(param.z0 + g*time*time)"}
    assert height.known_limits == {}
    motor = next(c for c in cases if c.id == "04_slider_motor").checks[0]
    assert motor.tolerance == {"default": "1e-9", "mujoco": "2e-6"}
    assert set(motor.known_limits) == {"ode", "drake", "newton", "mujoco_warp"}


@pytest.mark.parametrize(
    "case",
    ["10a_interval_blends", "10b_interval_takeover", "10c_interval_sequence", "11_collision_events"],
)
def test_runner_semantics_cases_pass_on_the_pure_python_backend(case: str) -> None:
    """Intervals and collision solids do not depend on the engine: they pass on `fake` too, exactly."""
    path = DEFAULT_SUITE / f"{case}.yaml"
    for variant in variant_names(path):
        result = run_case(path, None if variant == "base" else variant, "fake")
        assert result["status"] == "passed", result
        for check in result["checks"]:
            if check["target"] is not None and check["tol"] is not None:
                assert abs(check["measured"] - check["target"]) <= check["tol"] + 1e-12


def _anchors(doc: Path) -> set[str]:
    """GitHub's heading anchors: lower case, punctuation dropped, spaces to hyphens."""
    heads = [line.lstrip("#").strip() for line in doc.read_text().splitlines() if line.startswith("#")]
    return {re.sub(r"[^\w\- ]", "", h.lower()).replace(" ", "-") for h in heads}


@pytest.mark.parametrize("path", FILES, ids=[f.stem for f in FILES])
def test_every_known_limit_names_an_engine_and_a_doc_that_exists(path) -> None:  # noqa: ANN001 - a Path
    root = DEFAULT_SUITE.parents[1]
    for variant in variant_names(path):
        for a in load_scenario(path, None if variant == "base" else variant).model.assertions:
            for backend, limit in a.known_limits.items():
                assert backend in KNOWN_BACKENDS, f"{a.name}: unknown backend {backend}"
                file, _, anchor = limit.doc.partition("#")
                assert (root / file).is_file(), f"{a.name}: {limit.doc} does not exist"
                assert anchor in _anchors(root / file), f"{a.name}: {limit.doc}: no such heading"
                assert limit.measured > 0
