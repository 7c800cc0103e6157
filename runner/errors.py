"""The runner's part of the exception tree, and the CLI's exit codes.

The whole tree (the root and the backend branch live in :mod:`backends.errors`)::

    PhysicsScenariosError
    ├── ScenarioError                 bad input                       exit 2
    │   ├── ScenarioValidationError   file:line:column, field, expected, found
    │   └── UsageError                bad command-line use
    ├── BackendError                  backend or engine               exit 3
    │   ├── UnknownBackend            a name not in the registry      exit 2
    │   ├── BackendNotInstalled       engine missing (install hint)   exit 3
    │   ├── UnsupportedFeature        capability missing              exit 2
    │   └── EngineFailure             NaN, inf, blow-up, engine error exit 3
    │       ├── BudgetExceeded        over its wall-clock budget      exit 3
    │       └── EnergyGain            energy from nowhere             exit 3
    ├── TraceError                    an output path cannot be used   exit 2
    │   ├── OutputInUse               another run is writing it       exit 2
    │   └── OutputError               disk full, I/O error            exit 74
    └── InternalError                 a bug in this tool              exit 70
        └── ContractViolation         a backend contract misused

Which exception gives which exit code and first message line, on every execution path:
:func:`runner.exec.exits.classify`.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from backends.errors import (
    BackendError,
    BackendNotInstalled,
    ContractViolation,
    EngineFailure,
    InternalError,
    PhysicsScenariosError,
    UnknownBackend,
    UnsupportedFeature,
)

__all__ = [
    "BackendError",
    "BackendNotInstalled",
    "BudgetExceeded",
    "ContractViolation",
    "EnergyGain",
    "EngineFailure",
    "ExitCode",
    "InternalError",
    "Issue",
    "OutputError",
    "OutputInUse",
    "PhysicsScenariosError",
    "ScenarioError",
    "ScenarioValidationError",
    "TraceError",
    "UnknownBackend",
    "UnsupportedFeature",
    "UsageError",
]


class ExitCode(enum.IntEnum):
    #: every assertion of every run passed
    OK = 0
    #: at least one assertion failed
    ASSERTION_FAILED = 1
    #: bad input: a scenario, an option, a path
    BAD_INPUT = 2
    #: a backend or engine failed (missing engine, engine error, NaN or blow-up)
    ENGINE_FAILURE = 3
    #: a bug in this tool ("internal error, please report"); BSD sysexits' EX_SOFTWARE
    INTERNAL_ERROR = 70
    #: an output could not be written (disk full, I/O error); what was written is kept; sysexits' EX_IOERR
    OUTPUT_ERROR = 74
    #: interrupted by SIGINT (Ctrl-C)
    INTERRUPTED = 130
    #: terminated by SIGTERM
    TERMINATED = 143


@dataclass(frozen=True)
class Issue:
    """One problem in a scenario file, located."""

    file: str
    line: int  # 1-based; 0 when unknown
    column: int  # 1-based; 0 when unknown
    path: str  # the field, e.g. "bodies.box.density"
    message: str  # what was expected and what was found

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}:{self.column}" if self.line else self.file
        field = f" {self.path}:" if self.path else ""
        return f"{where}:{field} {self.message}"


class ScenarioError(PhysicsScenariosError):
    """Bad input (exit code 2)."""


class ScenarioValidationError(ScenarioError):
    """A scenario file is invalid; carries every located issue found."""

    def __init__(self, issues: list[Issue]) -> None:
        self.issues = issues
        super().__init__("\n".join(str(i) for i in issues))


class UsageError(ScenarioError):
    """The command line asks for something that cannot be done."""


class TraceError(PhysicsScenariosError):
    """A trace cannot be written or read."""


class OutputInUse(TraceError):
    """Another run is writing the same outputs (same scenario, variant and backend into the same folder)."""


class OutputError(TraceError):
    """Writing an output failed part-way (disk full, quota, I/O error); what was written is kept."""


class BudgetExceeded(EngineFailure):
    """A run went over its wall-clock budget (``world.budget`` or ``--timeout``), or its cost per step
    says it would; stopped at a step boundary, the trace finished."""


class EnergyGain(EngineFailure):
    """The bodies' mechanical energy rose beyond the bound with no work done on them (runner.sim.energy);
    stopped at the step that showed it, the trace finished."""
