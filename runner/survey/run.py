"""Run the survey: every model on every engine, through runner.exec like every other command's cases."""

from __future__ import annotations

from collections.abc import Callable

from runner.exec.cases import Case, CaseResult
from runner.exec.executors import make_executor
from runner.survey.cases import Refusal, survey_cases
from runner.survey.models import ROBOT, ModelFile
from runner.survey.table import CRASHED, RAN, REFUSED, Cell, Survey, cell_of

#: wall-clock seconds one run may take (a model that stalls an engine is a failed cell, not a stuck survey)
DEFAULT_TIMEOUT = 300.0


def run_survey(
    models: list[ModelFile],
    backends: list[str],
    duration: float,
    jobs: int = 1,
    timeout: float = DEFAULT_TIMEOUT,
    on_model: Callable[[str], None] | None = None,
) -> Survey:
    """The survey's table: a model the language refuses (or that this tool fails to load) has that cell on
    every engine; every other model runs once per engine."""
    survey = Survey(list(backends), duration)
    cases: list[Case] = []
    owners: list[str] = []
    notes: dict[str, str] = {}
    for model in models:
        built = survey_cases(model, backends, duration, timeout)
        if isinstance(built, Refusal):
            kind = REFUSED if built.kind == "refused" else CRASHED
            text = built.message if kind == REFUSED else f"exit 70: {built.message}"
            survey.rows[model.label] = dict.fromkeys(backends, Cell(kind, text))
            continue
        survey.rows[model.label] = {}
        cases += built
        owners += [model.label] * len(built)
        loaded = built[0].loaded if built else None
        notes[model.label] = "; ".join(loaded.robots[ROBOT].notes) if loaded is not None else ""

    def done(index: int, res: CaseResult) -> None:
        cell = cell_of(res)
        if cell.kind == RAN and notes[owners[index]]:  # what the loader decided for the file (a start clamped, ...)
            cell = Cell(RAN, notes[owners[index]])
        survey.rows[owners[index]][res.case.backend] = cell
        if on_model is not None and len(survey.rows[owners[index]]) == len(backends):
            on_model(owners[index])

    executor = make_executor("local", jobs)
    try:
        executor.run(cases, done)
    finally:
        executor.close()
    return survey
