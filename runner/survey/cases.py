"""A survey model's scenario, loaded in memory as a scenario file would be, and the cases that run it."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from runner.errors import Issue, ScenarioValidationError
from runner.exec.cases import Case, estimate_cost
from runner.language.load import LoadedScenario
from runner.language.model import Scenario
from runner.language.model_robots import Robot
from runner.language.refs import check_references
from runner.language.robot_desc import ModelFileError
from runner.language.robots import load_model, load_robots
from runner.language.times import time_context
from runner.language.yaml_source import load_yaml
from runner.survey.models import CLEARANCE, ModelFile, lowest_point, scenario_text


@dataclass(frozen=True)
class Refusal:
    """Why a model cannot be loaded at all (the same on every engine): the first problem, where it is."""

    message: str
    kind: str  # refused (bad input, exit 2) | crashed (a bug in this tool, exit 70)


def load_survey_scenario(model: ModelFile, duration: float) -> LoadedScenario:
    """The model's survey scenario (runner.survey.models), checked as `scenario run` checks a file; raises
    ScenarioValidationError for what the language refuses."""
    folder = model.path.parent
    try:
        desc = load_model(Robot.model_validate({model.format: model.path.name}), folder)
    except ModelFileError as exc:
        raise ScenarioValidationError([Issue(exc.file, exc.line, exc.column, f"robots.model.{model.format}",
                                             exc.message)]) from None  # fmt: skip
    fixed = model.format == "urdf" and desc.link(desc.root).mass <= 0
    text = scenario_text(model, CLEARANCE - lowest_point(desc), fixed, duration)
    path = folder / f"{model.path.name}.survey.yaml"  # never written: the scenario exists in memory only
    data, positions = load_yaml(text, str(path))
    try:
        scenario = Scenario.model_validate(data, context=time_context(data))
    except Exception as exc:  # noqa: BLE001 - a survey scenario the language refuses is this tool's bug
        raise RuntimeError(f"the survey built a scenario the language refuses: {exc}") from exc
    robots = load_robots(scenario, positions, folder)
    check_references(scenario, positions, folder, robots)
    return LoadedScenario(model=scenario, variant="base", path=path, text=text,
                          sha256=hashlib.sha256(text.encode()).hexdigest(), positions=positions, overrides=(),
                          robots=robots)  # fmt: skip


def survey_cases(model: ModelFile, backends: list[str], duration: float, timeout: float) -> list[Case] | Refusal:
    """One case per backend (no trace), or why the model cannot be loaded."""
    try:
        loaded = load_survey_scenario(model, duration)
    except ScenarioValidationError as exc:
        first = exc.issues[0]
        where = f"{Path(first.file).name}:{first.line}" if first.line else Path(first.file).name
        return Refusal(f"{where}: {first.message}", "refused")
    except Exception as exc:  # noqa: BLE001 - a bug met while loading one model must not stop the survey
        return Refusal(f"{type(exc).__name__}: {exc}", "crashed")
    return [
        Case(
            str(loaded.path),
            None,
            backend,
            (),
            None,
            cost=estimate_cost(loaded),
            budget=timeout,
            scenario=loaded.model.scenario,
            loaded=loaded,
        )  # fmt: skip
        for backend in backends
    ]
