"""JUnit XML for CI services: one testcase per scenario x variant x backend.

The file is valid against the Apache Ant JUnit schema that Jenkins, GitLab, GitHub test reporters and others
read (committed as tests/ci/junit.xsd): ``<testsuites>`` holds one ``<testsuite>`` per scenario and
backend, whose properties carry the backend, the engine's and the tool's versions and the scenario file, with
one ``<testcase name="VARIANT[BACKEND]" classname="SCENARIO">`` per variant. An assertion failure or a
divergence from a baseline is a ``<failure>``; bad input, a missing baseline or an engine failure is an
``<error>`` (the convention of scenario-testing tools); a run that passed with known limits (expected
failures, ``known_limits`` in the scenario) is ``<skipped message="known limit: ...">``. The schema allows
properties on suites only.

Times are the runs' wall-clock seconds and the timestamp the moment of writing (``SOURCE_DATE_EPOCH`` when
set): this file is a CI report, the one output with wall-clock figures; traces and golden files have none.
"""

from __future__ import annotations

import os
import platform
import re
import socket
import sys
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING

from runner.version import tool_version

if TYPE_CHECKING:
    from runner.ci.regression import CaseOutcome
    from runner.language.load import LoadedScenario
    from runner.sim.session import RunResult

_NOT_XML = re.compile("[^\x09\x0a\x0d\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


@dataclass
class JUnitCase:
    scenario: str
    variant: str
    backend: str
    outcome: str  # passed | failure | error | skipped
    seconds: float = 0.0
    kind: str = ""  # assertion | divergence | bad-input | missing-baseline | engine-failure
    message: str = ""
    text: str = ""
    properties: dict[str, str] = field(default_factory=dict)  # the suite's: the first case of a suite sets them
    output: str = ""  # a line for the suite's <system-out> (e.g. the trace's path)


def suite_properties(backend: str, loaded: LoadedScenario | None = None) -> dict[str, str]:
    from backends.errors import BackendError
    from backends.registry import engine_version

    try:
        version = engine_version(backend)
    except BackendError:  # a name the command line gave that is no backend (its error case says so)
        version = "unknown backend"
    props = {
        "backend": backend,
        "engine_version": version,
        "tool_version": tool_version(),
        "python": platform.python_version(),
        "platform": f"{sys.platform}-{platform.machine()}",
    }
    if loaded is not None:
        props["scenario_file"] = str(loaded.path)
        props["scenario_sha256"] = loaded.sha256
    return props


def from_result(result: RunResult, loaded: LoadedScenario | None = None) -> JUnitCase:
    """A case of `scenario run`: failed assertions are a failure, an engine failure an error."""
    from runner.ci.render import verdict_text

    case = JUnitCase(
        result.scenario, result.variant, result.backend, "passed", result.wall_seconds,
        properties=suite_properties(result.backend, loaded), output=f"trace: {result.trace}" if result.trace else "",
    )  # fmt: skip
    if result.status == "engine-failure":
        case.outcome, case.kind, case.message = "error", "engine-failure", result.failure or "engine failure"
        case.text = case.message + (f"\nlast good state: {result.extra.get('last_good')}" if result.extra else "")
    elif not result.passed:
        failed = [v.name for v in result.verdicts if not v.passed]
        case.outcome, case.kind = "failure", "assertion"
        case.message = f"{len(failed)} assertion(s) failed: {', '.join(failed)}"
        case.text = verdict_text(result)
    else:
        _known_limits(case, result)
    return case


def _known_limits(case: JUnitCase, result: RunResult) -> None:
    """A run that passed only because of known limits (expected failures) is ``<skipped>`` with them named:
    CI reports show it apart from a pass, and it does not fail the build."""
    from runner.ci.render import known_limit_lines

    limits = known_limit_lines(result)
    if limits:
        case.outcome, case.kind = "skipped", "known-limit"
        case.message = "; ".join(limits)


def from_outcome(outcome: CaseOutcome) -> JUnitCase:
    """A case of `scenario check`: a divergence or a failed assertion is a failure; no baseline, a bad one, or a
    run that did not complete (bad input, an engine failure, a crash, a full disk) is an error, with the first
    line `scenario run` gives."""
    from runner.ci.regression import comparison_lines, outcome_text

    loaded, result = outcome.loaded, outcome.result
    case = JUnitCase(
        loaded.model.scenario, loaded.variant, outcome.backend, "passed", outcome.run.wall_seconds,
        properties=suite_properties(outcome.backend, loaded),
        output=f"trace: {outcome.run.trace}" if outcome.run.trace else "",
    )  # fmt: skip
    exit = outcome.exit
    if outcome.outcome == "error":
        output = outcome.run.output.strip()[-2000:]
        case.outcome, case.kind, case.message = "error", outcome.error_kind, exit.headline
        case.text = outcome_text(outcome, details=output or None)
    elif outcome.outcome == "failure":
        case.outcome = "failure"
        reasons = []
        if outcome.comparison is not None and not outcome.comparison.ok:
            case.kind = "divergence"
            reasons.append(comparison_lines(outcome.comparison)[0])
        if result is not None and not result.passed:
            case.kind = case.kind or "assertion"
            reasons.append(outcome.run.exit.headline)  # "failed: 1 of 2 assertions: ..."
        case.message = "; ".join(reasons)
        case.text = outcome_text(outcome)
    elif result is not None:
        _known_limits(case, result)
    return case


def from_error(
    file: Path | str, backend: str, message: str, kind: str = "bad-input", variant: str = "load"
) -> JUnitCase:
    """A case that could not run: the file's stem stands for the scenario's name."""
    return JUnitCase(
        Path(file).stem, variant, backend, "error", kind=kind, message=message, text=message,
        properties={**suite_properties(backend), "scenario_file": str(file)},
    )  # fmt: skip


def _clean(text: str) -> str:
    return _NOT_XML.sub("", _ANSI.sub("", text))


def _timestamp() -> str:
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    when = datetime.fromtimestamp(int(epoch), timezone.utc) if epoch and epoch.isdigit() else datetime.now(timezone.utc)
    return when.strftime("%Y-%m-%dT%H:%M:%S")  # the schema's pattern: no fraction, no zone (UTC)


def to_xml(cases: Sequence[JUnitCase], timestamp: str | None = None, hostname: str | None = None) -> bytes:
    suites: dict[tuple[str, str], list[JUnitCase]] = {}
    for case in cases:
        suites.setdefault((case.scenario, case.backend), []).append(case)
    stamp = timestamp or _timestamp()
    host = hostname or socket.gethostname() or "localhost"
    root = ET.Element("testsuites")
    for index, ((scenario, backend), members) in enumerate(suites.items()):
        name = _clean(f"{scenario}.{backend}")
        suite = ET.SubElement(root, "testsuite", {
            "name": name, "package": name, "id": str(index), "timestamp": stamp, "hostname": host,
            "tests": str(len(members)),
            "failures": str(sum(c.outcome == "failure" for c in members)),
            "errors": str(sum(c.outcome == "error" for c in members)),
            "skipped": str(sum(c.outcome == "skipped" for c in members)),
            "time": f"{sum(c.seconds for c in members):.3f}",
        })  # fmt: skip
        props = ET.SubElement(suite, "properties")
        for key, value in members[0].properties.items():
            ET.SubElement(props, "property", {"name": key, "value": _clean(str(value))})
        for case in members:
            attrs = {"name": _clean(f"{case.variant}[{case.backend}]"), "classname": _clean(case.scenario),
                     "time": f"{max(case.seconds, 0.0):.3f}"}  # fmt: skip
            element = ET.SubElement(suite, "testcase", attrs)
            if case.outcome in ("failure", "error"):
                child = ET.SubElement(
                    element, case.outcome, {"message": _clean(case.message), "type": case.kind or case.outcome}
                )
                child.text = _clean(case.text)
            elif case.outcome == "skipped":
                ET.SubElement(element, "skipped", {"message": _clean(case.message)} if case.message else {})
        ET.SubElement(suite, "system-out").text = _clean("\n".join(c.output for c in members if c.output))
        ET.SubElement(suite, "system-err").text = ""
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True) + b"\n"


def write_junit(path: Path, cases: Sequence[JUnitCase]) -> Path:
    """Write the JUnit file (to a temporary name, then renamed: a half-written report never looks finished)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    tmp.write_bytes(to_xml(cases))
    tmp.replace(path)
    return path
