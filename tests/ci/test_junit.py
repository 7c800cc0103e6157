"""JUnit reports of `run` and `check`, validated against the Ant/Jenkins JUnit schema (tests/ci/junit.xsd)
with `xmlschema` (a dev dependency)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import xmlschema

from backends.registry import engine_version
from runner.ci.junit import JUnitCase, to_xml
from runner.version import tool_version

from .conftest import FACTORY, SCHEMA, cli

# A box dropped from 2 m, dt 0.04. Semi-implicit Euler gives z_n = 2 - g dt^2 n(n+1)/2: at t = 0.4 (n = 10)
# z = 2 - 9.81 * 0.0016 * 55 = 1.13672. `wrong` expects it to stay at 2 (a failure); `blow-up` kicks the 13.5 kg
# box with 1e9 N for one step (v = 3e6 m/s, beyond the runner's 1e4 m/s limit: an engine failure). It runs on the
# `fake` backend (exact semi-implicit Euler, no contacts): these tests are about the report, and PyBullet caps a
# free body's speed at 100 m/s, so it cannot blow up this way.
DROP = """\
schema_version: 1
scenario: drop
world: {gravity: [0, 0, -9.81], dt: 0.04, duration: 0.4}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 2]}
variants:
  falls:
    assertions: [{name: free-fall, at: 0.4, value: box.pos.z, near: 2 - g*dt*dt*55, tol: 1e-4}]
  wrong:
    assertions: [{name: stays-up, at: 0.4, value: box.pos.z, near: 2, tol: 1e-3}]
  blow-up:
    set: {on: {start: [{force: {body: box, value: [0, 0, 1.0e9]}}]}}
"""


@pytest.fixture(scope="module")
def schema() -> xmlschema.XMLSchema:
    return xmlschema.XMLSchema(str(SCHEMA))


def _cases(path: Path) -> dict[str, ET.Element]:
    return {c.get("name", ""): c for c in ET.parse(path).getroot().iter("testcase")}


def test_run_junit_failure_error_and_properties(
    schema: xmlschema.XMLSchema, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    drop = tmp_path / "drop.yaml"
    drop.write_text(DROP)
    report = tmp_path / "junit.xml"
    code, output = cli(capsys, "run", drop, "--all-variants", "-b", "fake", "--out", tmp_path / "t", "--junit", report)
    assert code == 3, output  # an engine failure wins over an assertion failure
    schema.validate(str(report))
    suite = ET.parse(report).getroot().find("testsuite")
    assert suite is not None
    assert (suite.get("name"), suite.get("tests"), suite.get("failures"), suite.get("errors")) == (
        "drop.fake", "3", "1", "1"
    )  # fmt: skip
    props = {p.get("name"): p.get("value") for p in suite.iter("property")}
    assert props["backend"] == "fake" and props["engine_version"] == engine_version("fake")
    assert props["tool_version"] == tool_version() and props["scenario_file"] == str(drop)
    cases = _cases(report)
    assert list(cases) == ["falls[fake]", "wrong[fake]", "blow-up[fake]"]
    assert len(cases["falls[fake]"]) == 0  # passed: no child
    failure = cases["wrong[fake]"].find("failure")
    assert failure is not None and failure.get("type") == "assertion"
    assert "stays-up" in (failure.get("message") or "") and "| stays-up" in (failure.text or "")
    error = cases["blow-up[fake]"].find("error")
    assert error is not None and error.get("type") == "engine-failure"
    assert "body `box` reached a speed above 10000" in (error.get("message") or "")


def test_run_junit_bad_input_is_an_error(
    schema: xmlschema.XMLSchema, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(DROP.replace("density: 500", "densty: 500"))
    report = tmp_path / "junit.xml"
    code, output = cli(capsys, "run", bad, "--junit", report)
    assert code == 2, output
    schema.validate(str(report))
    error = _cases(report)["load[pybullet]"].find("error")
    assert error is not None and error.get("type") == "bad-input"
    assert "unknown key `densty`; did you mean `density`?" in (error.text or "")


@pytest.mark.parametrize("backends", [["-b", "fake,pybullet"], ["-b", "fake", "-b", "pybullet"], ["-b", "nosuch"]])
def test_run_junit_bad_input_with_several_backends_is_an_error_per_backend(
    schema: xmlschema.XMLSchema, tmp_path: Path, capsys: pytest.CaptureFixture[str], backends: list[str]
) -> None:
    """Before: `-b a,b --junit` on a bad file printed "Unknown backend `a,b`" (the JUnit writer looked the joined
    names up) instead of the file's own errors."""
    bad = tmp_path / "bad.yaml"
    bad.write_text(DROP.replace("density: 500", "densty: 500"))
    report = tmp_path / "junit.xml"
    code, output = cli(capsys, "run", bad, *backends, "--junit", report)
    assert code == 2, output
    expected = "Unknown backend `nosuch`" if "nosuch" in backends else "unknown key `densty`"  # names come first
    assert expected in output and "Unknown backend `fake,pybullet`" not in output, output
    schema.validate(str(report))
    names = [n for n in backends if n != "-b"][0].split(",") + [n for n in backends if n != "-b"][1:]
    cases = _cases(report)
    assert sorted(cases) == sorted(f"load[{n}]" for n in names), list(cases)
    for case in cases.values():
        error = case.find("error")
        assert error is not None and expected in (error.text or "")


def test_check_junit_divergence_and_missing_baseline(
    schema: xmlschema.XMLSchema, factory_goldens: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    copy = tmp_path / "slippery.yaml"
    copy.write_text(FACTORY.read_text().replace("surface: {bounce: 0.2,", "surface: {bounce: 0.5,", 1))
    report = tmp_path / "check.xml"
    args = ["check", copy, "--variant", "door-stays-closed", "--out", tmp_path / "t"]
    assert cli(capsys, *args, "--baseline", factory_goldens, "--junit", report)[0] == 1
    schema.validate(str(report))
    failure = _cases(report)["door-stays-closed[pybullet]"].find("failure")
    assert failure is not None and failure.get("type") == "divergence"
    assert (failure.get("message") or "").startswith("first divergence: t=1 s, body `box`")
    assert cli(capsys, *args, "--baseline", tmp_path / "none", "--junit", report)[0] == 2
    schema.validate(str(report))
    error = _cases(report)["door-stays-closed[pybullet]"].find("error")
    assert error is not None and error.get("type") == "missing-baseline"


def test_text_is_cleaned_for_xml(schema: xmlschema.XMLSchema) -> None:
    case = JUnitCase("odd", "v", "fake", "failure", 0.5, "assertion", "bell\x07 and \x1b[31mred\x1b[0m", "a < b & c")
    data = to_xml([case], timestamp="2024-01-02T03:04:05", hostname="ci")
    schema.validate(data.decode())
    failure = ET.fromstring(data).find("testsuite/testcase/failure")
    assert failure is not None and failure.get("message") == "bell and red" and failure.text == "a < b & c"
