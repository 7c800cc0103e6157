"""A pytest plugin: ``pytest scenarios/`` runs each scenario x variant x backend as a test item.

Registered through the ``pytest11`` entry point ``runner.ci.pytest_plugin`` (or load it with
``-p runner.ci.pytest_plugin``; ``-p no:runner.ci.pytest_plugin`` turns it off). Item ids read
``scenarios/factory_physics.yaml::door-stays-closed[pybullet]``. Each case runs through ``runner.exec`` as
`scenario run` runs it, and its report starts with the first line `run` prints for it and `run`'s exit code
(``failed: 1 of 2 assertions: stays-up [exit 1]``): a failed assertion (or a divergence from a baseline) is a
pytest *failure* followed by the verdict table (and the first divergence); a case that does not complete
(bad input, a capability its engine lacks, a missing engine, a crash, a full disk) is a pytest *error*,
never a traceback into the runner. pytest's own exit code is then 1 for both (docs/reliability.md).

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
them in `run`'s words; a known limit that passes fails the item (strict).
Imports stay light here: the runner is imported only when a scenario file is collected.
"""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any, NoReturn

import pytest

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


class ScenarioItem(pytest.Item):
    """One scenario x variant x backend: it passes when every assertion passes (and the baseline matches).

    The case runs in ``setup`` through runner.exec, as `scenario run` runs it. One that does not complete
    (bad input, a capability its engine lacks, a missing engine, a crash, a full disk, a bug) is a pytest
    *error* whose first line is the one `run` prints, with `run`'s exit code; a failed assertion or a
    divergence is a *failure* (in ``runtest``); a pass with known limits an xfail naming them."""

    def __init__(self, *, variant: str, backend: str, problem: str = "", **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.variant, self.backend, self.problem = variant, backend, problem
        self.add_marker("scenario")
        if backend:
            self.user_properties.append(("backend", backend))
        self._failure = ""  # the report of a failed assertion or a divergence, for runtest
        self._limits: list[str] = []

    def setup(self) -> None:
        if self.problem:  # the file could not be read: `run` refuses it as bad input (exit 2)
            self._error(f"error: {self.problem}", 2)
        from backends.registry import engine_version
        from runner.errors import ExitCode, PhysicsScenariosError
        from runner.exec.exits import classify

        try:
            self.user_properties.append(("engine_version", engine_version(self.backend)))
            text, code, limits = self._run()
        except PhysicsScenariosError as exc:  # refused before the case could run: an unknown backend
            exit = classify(exc)
            self._error(exit.headline, exit.code)
        if code in (ExitCode.INTERRUPTED, ExitCode.TERMINATED):
            raise KeyboardInterrupt  # pytest stops, as `run` does
        if code not in (ExitCode.OK, ExitCode.ASSERTION_FAILED):
            self._error(text, code)
        self.user_properties.append(("exit_code", int(code)))
        self._failure = text if code == ExitCode.ASSERTION_FAILED else ""
        self._limits = limits

    def _error(self, text: str, code: int) -> NoReturn:
        """The item is a pytest error (raised in setup), reported as its text alone (pytest_runtest_makereport)."""
        self.user_properties.append(("exit_code", int(code)))
        raise ScenarioCaseError(_with_code(text, code))

    def _run(self) -> tuple[str, int, list[str]]:
        """The case run (and checked): its report text, exit code, and known-limit lines."""
        from runner.ci.regression import CaseOutcome, check_cases, outcome_text, run_cases
        from runner.ci.render import known_limit_lines
        from runner.language.load import load_scenario

        loaded = load_scenario(self.path, None if self.variant == BASE_CASE else self.variant)
        baseline, out = _baseline(self.config), _out(self.config)
        if baseline is not None:
            (outcome,) = check_cases([(loaded, self.backend)], baseline, out)
        else:
            (res,) = run_cases([(loaded, self.backend)], out)
            outcome = CaseOutcome(loaded, res, Path())
        exit = outcome.exit
        details = _details(outcome)
        return outcome_text(outcome, details=details), exit.code, known_limit_lines(outcome.result)

    def runtest(self) -> None:
        if self._failure:  # a known limit that now passes fails here: strict, as xfail(strict=True)
            raise ScenarioCaseError(_with_code(self._failure, 1))
        if self._limits:  # expected failures: named with the words `run` prints
            pytest.xfail("; ".join(self._limits))

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        if isinstance(excinfo.value, ScenarioCaseError):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, None, f"{self.path.name}::{self.name}"


def _with_code(text: str, code: int) -> str:
    """``<first line> [exit N]``: the first line `scenario run` prints for the case, and its exit code."""
    first, _, rest = text.partition("\n")
    return f"{first} [exit {code}]" + (f"\n{rest}" if rest else "")


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Any:
    """A scenario item's error in setup is reported as its text, as a failure in the call is (repr_failure):
    no traceback into the runner, and no exception name before `run`'s first line."""
    report = yield
    if isinstance(item, ScenarioItem) and call.excinfo is not None and call.when == "setup":
        if isinstance(call.excinfo.value, ScenarioCaseError):
            report.longrepr = str(call.excinfo.value)
    return report


def _details(outcome: Any) -> str:
    """What explains a case that did not complete, as `run` prints it: every located issue, the engine's last
    output of a crash, the trace it kept."""
    res = outcome.run
    lines = [str(i) for i in getattr(res.error, "issues", None) or []]
    if res.status in ("crashed", "exited") and res.output.strip():
        lines.append(res.output.strip()[-2000:])
    if res.trace is not None:
        lines.append(f"trace: {res.trace}")
    return "\n".join(lines)
