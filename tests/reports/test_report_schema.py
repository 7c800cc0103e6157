"""report.json follows its documented JSON Schema (docs/report.schema.json), for a run that crashed and
for one with sounds; and the schema refuses what it should."""

from __future__ import annotations

import copy
import json

import jsonschema
import pytest

from .conftest import ROOT, CompareRun, SoundReport

SCHEMA = json.loads((ROOT / "docs" / "report.schema.json").read_text(encoding="utf-8"))


def _validator() -> jsonschema.Draft202012Validator:
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    return jsonschema.Draft202012Validator(SCHEMA)


def test_reports_follow_the_schema(compare_run: CompareRun, sound_report: SoundReport) -> None:
    validator = _validator()
    validator.validate(compare_run.doc)
    sounds = json.loads((sound_report.out / "report.json").read_text(encoding="utf-8"))
    validator.validate(sounds)
    thud = [s for s in sounds["cases"][0]["sounds"]["ode"] if s["name"] == "thud" and s["action"] == "start"]
    assert len(thud) == 1 and thud[0]["t"] == pytest.approx(2.16)  # the box-into-door handler plays it


def test_the_schema_refuses_a_wrong_report(compare_run: CompareRun) -> None:
    validator = _validator()
    doc = copy.deepcopy(compare_run.doc)
    doc["cases"][0]["runs"][0]["status"] = "fine"
    assert not validator.is_valid(doc)
    doc = copy.deepcopy(compare_run.doc)
    del doc["cases"][0]["quantities"][0]["deviation"]["ode"]["max"]
    assert not validator.is_valid(doc)
    doc = copy.deepcopy(compare_run.doc)
    doc["headline"]["badge"] = "OK"
    assert not validator.is_valid(doc)
    doc = copy.deepcopy(compare_run.doc)
    doc["cases"][0]["quantities"][0]["truth"] = {"kind": "reference"}
    assert not validator.is_valid(doc)
