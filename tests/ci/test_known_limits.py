"""Known limits (an assertion's ``known_limits``) are expected failures on every output: the verdict, `run`'s
exit code and table, the trace's /verdicts and /log, JUnit (``<skipped>``, valid against the Ant schema), the
pytest plugin (xfail, strict), `inspect`, `sweep` and the compare report. The logic runs on the `fake` backend
(exact semi-implicit Euler: the free fall's numbers are known to the last bit); tests/exec/test_exit_codes.py
runs a known limit through every execution path on PyBullet."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import jsonschema
import pytest
import xmlschema

from reports.markdown import text as md_text
from reports.trace_reader import read_trace
from runner.language.load import load_scenario
from runner.sim.run import run_loaded
from tests.paths import ROOT

from .conftest import SCHEMA, cli
from .test_pytest_plugin import PLUGIN, pytest_run

# A box dropped from 2 m at dt 0.04: z(0.4) = 2 - g dt^2 55 = 1.13672 exactly on `fake`. `limited` expects it
# 0.01 m higher (fails at tol 1e-4: a known limit on fake); `gone` expects the exact value (passes: the known
# limit is no longer needed); `other` is a known limit of another engine only (judged as written on fake).
LIMIT = "{measured: 0.01, cause: the test's own offset, doc: docs/language.md#assertions}"
DROP = f"""\
schema_version: 1
scenario: drop
world: {{gravity: [0, 0, -9.81], dt: 0.04, duration: 0.4}}
bodies:
  box: {{box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 2]}}
variants:
  limited:
    assertions:
      - {{name: height, at: 0.4, value: box.pos.z, near: 2.01 - g*dt*dt*55, tol: 1e-4, known_limits: {{fake: {LIMIT}}}}}
      - {{name: falls, at: end, check: box.vel.z < 0}}
  gone:
    assertions:
      - {{name: height, at: 0.4, value: box.pos.z, near: 2 - g*dt*dt*55, tol: 1e-4, known_limits: {{fake: {LIMIT}}}}}
  other:
    assertions:
      - {{name: height, at: 0.4, value: box.pos.z, near: 2.01 - g*dt*dt*55, tol: 1e-4, known_limits: {{ode: {LIMIT}}}}}
"""
MESSAGE = "known limit on fake: measured 0.01 (documented 0.01); the test's own offset (docs/language.md#assertions)"


@pytest.fixture
def drop(tmp_path: Path) -> Path:
    path = tmp_path / "drop.yaml"
    path.write_text(DROP)
    return path


def test_the_verdicts_and_the_trace(drop: Path, tmp_path: Path) -> None:
    runs = {v: run_loaded(load_scenario(drop, v), "fake", tmp_path / v) for v in ("limited", "gone", "other")}
    assert {v: r.status for v, r in runs.items()} == {"limited": "passed", "gone": "failed", "other": "failed"}
    limited = runs["limited"].verdicts[0]
    assert (limited.status, limited.passed, limited.message) == ("known limit", True, MESSAGE)
    assert limited.deviation == pytest.approx(0.01, abs=1e-12) and limited.tolerance == 1e-4  # the default tol
    gone = runs["gone"].verdicts[0]
    assert (gone.status, gone.message) == (
        "failed",
        "known limit no longer needed: height on fake now passes; remove it",
    )
    assert runs["other"].verdicts[0].known_limit is None  # another engine's known limit: judged as written
    trace = read_trace(runs["limited"].trace or "")
    assert [v.status for v in trace.verdicts] == ["known limit", "passed"]
    assert trace.verdicts[0].data["known_limit"] == {
        "measured": 0.01, "cause": "the test's own offset", "doc": "docs/language.md#assertions"
    }  # fmt: skip
    logs = [log.message for log in trace.logs if log.name == "verdict"]
    assert f"KNOWN LIMIT height: measured 1.13672 (expected 1.14672 ± 0.0001); {MESSAGE}" in logs
    assert "1/2 assertions passed; known limits: height" in logs
    assert read_trace(runs["gone"].trace or "").verdicts[0].status == "failed"  # it names the entry, yet fails
    assert "known_limit" not in read_trace(runs["other"].trace or "").verdicts[0].data  # absent without one


def test_run_prints_it_apart_and_junit_skips_it(drop: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    report = tmp_path / "junit.xml"
    code, output = cli(capsys, "run", drop, "--variant", "limited", "-b", "fake", "--out", tmp_path / "t",
                       "--junit", report)  # fmt: skip
    assert code == 0, output
    assert "known limit" in output and "1/1 runs passed (1/2 assertions, 1 known limit)" in output
    assert "drop · limited · fake: known limit: height on fake: measured 0.01 (documented 0.01)" in output
    xmlschema.XMLSchema(str(SCHEMA)).validate(str(report))
    suite = ET.parse(report).getroot().find("testsuite")
    assert suite is not None and (suite.get("skipped"), suite.get("failures")) == ("1", "0")
    skipped = suite.find("testcase/skipped")
    assert (
        skipped is not None and skipped.get("message") == f"known limit: height {MESSAGE.removeprefix('known limit ')}"
    )
    code, output = cli(capsys, "run", drop, "--variant", "gone", "-b", "fake", "--out", tmp_path / "g",
                       "--junit", report)  # fmt: skip
    assert code == 1 and "known limit no longer needed: height on fake now passes; remove it" in output
    xmlschema.XMLSchema(str(SCHEMA)).validate(str(report))
    assert ET.parse(report).getroot().find("testsuite/testcase/failure") is not None


def test_inspect_and_sweep(drop: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, output = cli(capsys, "sweep", drop, "--variant", "limited", "-b", "fake", "--param", "world.dt=0.04,0.02",
                       "--out", tmp_path / "s")  # fmt: skip
    assert code == 0, output
    table = json.loads((tmp_path / "s" / "sweep.json").read_text())
    assert [r["verdicts"]["height"]["status"] for r in table["rows"]] == ["known limit", "known limit"]
    assert (tmp_path / "s" / "sweep.csv").read_text().count(",known limit,pass,") == 2
    trace = next((tmp_path / "s").rglob("*.mcap"))
    code, output = cli(capsys, "inspect", trace)
    assert code == 0 and "known limit" in output


def test_compare_report_shows_the_figure(drop: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, output = cli(capsys, "compare", drop, "--variant", "limited", "--backends", "fake", "--out", tmp_path / "c")
    assert code == 0, output
    assert "known limit: height on fake: measured 0.01" in output
    doc = json.loads((tmp_path / "c" / "report.json").read_text())
    jsonschema.Draft202012Validator(json.loads((ROOT / "docs" / "report.schema.json").read_text())).validate(doc)
    run = doc["cases"][0]["runs"][0]
    assert run["assertions"] == {"total": 2, "passed": 1, "failed": 0, "known_limits": 1}
    assert doc["cases"][0]["verdicts"]["cells"]["height"]["fake"]["status"] == "known limit"
    markdown = (tmp_path / "c" / "report.md").read_text()
    assert "✅ 1/2, ⚠️ 1 known limit" in markdown and f"**height** ⚠️ {md_text(MESSAGE)}" in markdown
    assert "⚠ known limit" in (tmp_path / "c" / "report.html").read_text()


def test_pytest_plugin_xfails_it_and_fails_when_it_passes(drop: Path, tmp_path: Path) -> None:
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    done = pytest_run(tmp_path, "-p", PLUGIN, str(drop), "--scenario-backends", "fake", "-rfxX",
                      "--scenario-out", str(tmp_path / "out"), "-k", "not other")  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr
    assert f"XFAIL drop.yaml::limited[fake] - known limit: height {MESSAGE.removeprefix('known limit ')}" in done.stdout
    assert "1 failed, 1 deselected, 1 xfailed" in done.stdout
    assert "FAILED drop.yaml::gone[fake]" in done.stdout and "known limit no longer needed" in done.stdout
