"""A pytest plugin: ``pytest scenarios/`` runs each scenario x variant x backend as a test item.

Registered through the ``pytest11`` entry point ``runner.ci.pytest_plugin`` (or load it with
``-p runner.ci.pytest_plugin``; ``-p no:runner.ci.pytest_plugin`` turns it off). Item ids read
``scenarios/factory_physics.yaml::door-stays-closed[pybullet]``; a failing item is reported as its verdict table
(and, with a baseline, its first divergence), never as a traceback into the runner.

It collects a ``.yaml``/``.yml`` file only when asked and only when the file is a scenario (a top-level
``schema_version:`` or ``scenario:`` key):

* the file is under a path named on the command line that is not under the ini ``testpaths`` (so
  ``pytest scenarios/`` collects, and ``pytest`` or ``pytest tests/`` never collect YAML fixtures), or
* the file is under a path listed in the ini option ``scenario_paths``, whenever pytest visits it (add the
  folder to ``testpaths`` too to have a bare ``pytest`` run the scenarios).

Options: ``--scenario-backends a,b`` (ini ``scenario_backends``; default every installed backend),
``--scenario-baseline DIR`` (ini ``scenario_baseline``: also compare each case with its golden file),
``--scenario-out DIR`` (traces and divergence plots; default ``.pytest_cache/d/scenario-traces``).
A run that passes with known limits (an assertion's ``known_limits``: expected failures) is an xfail naming
them; a known limit that passes fails the item (strict).
Imports stay light here: the runner is imported only when a scenario file is collected.
"""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from runner.sim.session import RunResult

BASE_CASE = "base"  # runner.language.load.BASE_CASE: a file without variants runs as this one case
_ROOTS = pytest.StashKey[tuple[list[Path], list[Path], list[Path]]]()


class ScenarioCaseError(Exception):
    """A case that failed or could not run; its text is the whole report."""


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("scenario", "physics scenarios (runner.ci.pytest_plugin)")
    group.addoption(
        "--scenario-backends",
        metavar="NAMES",
        help="comma-separated backends for scenario items, or `installed` (default: ini scenario_backends, "
        "else every installed backend)",
    )
    group.addoption("--scenario-baseline", metavar="DIR", help="also compare each case with its golden file in DIR")
    group.addoption(
        "--scenario-out", metavar="DIR", help="traces and divergence plots (default .pytest_cache/d/scenario-traces)"
    )
    parser.addini("scenario_paths", type="paths", default=[], help="scenario files or folders always collected")
    parser.addini("scenario_backends", default="", help="comma-separated backends for scenario items")
    parser.addini("scenario_baseline", default="", help="folder of golden files to compare each case with")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "scenario: a physics scenario case collected from a YAML file")


def _under(path: Path, root: Path) -> bool:
    return path == root or root in path.parents


def _roots(config: pytest.Config) -> tuple[list[Path], list[Path], list[Path]]:
    if _ROOTS not in config.stash:
        named: list[Path] = []
        if config.args_source == pytest.Config.ArgsSource.ARGS:
            base = config.invocation_params.dir
            named = [(base / str(arg).split("::")[0]).resolve() for arg in config.args]
        listed = [Path(p).resolve() for p in config.getini("scenario_paths")]
        testpaths = [(config.rootpath / str(p)).resolve() for p in config.getini("testpaths")]
        config.stash[_ROOTS] = (named, listed, testpaths)
    return config.stash[_ROOTS]


def _asked(config: pytest.Config, path: Path) -> bool:
    named, listed, testpaths = _roots(config)
    path = path.resolve()
    if any(_under(path, root) for root in listed):
        return True
    return any(_under(path, root) for root in named) and not any(_under(path, t) for t in testpaths)


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    if file_path.suffix not in (".yaml", ".yml") or not _asked(parent.config, file_path):
        return None
    from runner.language.files import is_scenario  # the rule `scenario run FOLDER` follows too

    if not is_scenario(file_path):
        return None
    return ScenarioFile.from_parent(parent, path=file_path)


def _backends(config: pytest.Config) -> list[str]:
    value = config.getoption("--scenario-backends") or config.getini("scenario_backends") or "installed"
    wanted = [n.strip() for n in str(value).split(",") if n.strip()]
    if "installed" in wanted:
        from backends.registry import installed_backends  # imported only when needed: it loads numpy

        at = wanted.index("installed")
        wanted[at : at + 1] = installed_backends()
    return list(dict.fromkeys(wanted))


def _baseline(config: pytest.Config) -> Path | None:
    value = config.getoption("--scenario-baseline") or config.getini("scenario_baseline")
    if not value:
        return None
    path = Path(value)
    return path if path.is_absolute() else (config.invocation_params.dir / path)


def _out(config: pytest.Config) -> Path:
    value = config.getoption("--scenario-out")
    if value:
        return Path(value)
    cache = getattr(config, "cache", None)
    return cache.mkdir("scenario-traces") if cache is not None else Path(tempfile.mkdtemp(prefix="scenario-traces-"))


class ScenarioFile(pytest.File):
    """A scenario YAML file: one item per variant and backend."""

    def collect(self) -> Iterator[pytest.Item]:
        from runner.errors import ScenarioValidationError
        from runner.language.yaml_source import load_yaml  # light: the full loader runs in the items

        try:
            data, _ = load_yaml(self.path.read_text(encoding="utf-8"), str(self.path))
        except (ScenarioValidationError, OSError, UnicodeDecodeError) as exc:
            yield ScenarioItem.from_parent(self, name="load", variant="", backend="", problem=str(exc))
            return
        found = data.get("variants") if isinstance(data, dict) else None
        variants = list(found) if isinstance(found, dict) and found else [BASE_CASE]
        for variant in variants:
            for backend in _backends(self.config):
                yield ScenarioItem.from_parent(self, name=f"{variant}[{backend}]", variant=variant, backend=backend)


def _xfail_known_limits(result: RunResult | None) -> None:
    """A run that passed with known limits (expected failures) is an xfail naming them, as `scenario run`
    prints them; one whose known limit passes failed already (the runner's verdict)."""
    limits = [v for v in result.verdicts if v.status == "known limit"] if result is not None else []
    if limits:
        pytest.xfail("; ".join(f"{v.name}: {v.message}" for v in limits))


class ScenarioItem(pytest.Item):
    """One scenario x variant x backend: it passes when every assertion passes (and the baseline matches)."""

    def __init__(self, *, variant: str, backend: str, problem: str = "", **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.variant, self.backend, self.problem = variant, backend, problem
        self.add_marker("scenario")
        if backend:
            self.user_properties.append(("backend", backend))

    def runtest(self) -> None:
        from runner.errors import PhysicsScenariosError

        if self.problem:
            raise ScenarioCaseError(self.problem)
        try:
            self._run()
        except PhysicsScenariosError as exc:  # bad input, missing engine, unsupported feature
            raise ScenarioCaseError(f"{type(exc).__name__}: {exc}") from None

    def _run(self) -> None:
        from backends.registry import engine_version
        from runner.ci.regression import PASSED, check_case, outcome_text, verdict_text
        from runner.language.load import load_scenario
        from runner.sim.run import run_loaded

        loaded = load_scenario(self.path, None if self.variant == BASE_CASE else self.variant)
        self.user_properties.append(("engine_version", engine_version(self.backend)))
        baseline, out = _baseline(self.config), _out(self.config)
        if baseline is not None:
            outcome = check_case(loaded, self.backend, baseline, out)
            if outcome.outcome != PASSED:
                raise ScenarioCaseError(outcome_text(outcome))
            _xfail_known_limits(outcome.result)
            return
        result = run_loaded(loaded, self.backend, out)
        if not result.passed:  # a known limit that now passes fails here: strict, as xfail(strict=True)
            head = f"{loaded.model.scenario} · {loaded.variant} · {self.backend}: {result.status}"
            failure = f"\n{result.failure}" if result.failure else ""
            trace = f"\ntrace: {result.trace}" if result.trace else ""
            raise ScenarioCaseError(f"{head}{failure}\n{verdict_text(result)}{trace}")
        _xfail_known_limits(result)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        if isinstance(excinfo.value, ScenarioCaseError):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, None, f"{self.path.name}::{self.name}"
