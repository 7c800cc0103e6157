"""The `scenario` command: a thin layer that parses arguments, calls the library and maps errors to exit codes.

Exit codes (runner.errors.ExitCode): 0 all assertions passed; 1 an assertion failed; 2 bad input (scenario,
option, path, unknown backend, unsupported feature); 3 backend or engine failure (missing engine, engine
error, NaN or blow-up); 130 interrupted (SIGINT); 143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import importlib
import json
import pkgutil
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from rich.console import Console
from rich.markup import escape

from reports.trace_reader import TraceReadError
from runner import interrupts
from runner.errors import (
    BackendNotInstalled,
    EngineFailure,
    ExitCode,
    PhysicsScenariosError,
    ScenarioError,
    ScenarioValidationError,
    TraceError,
    UnknownBackend,
    UnsupportedFeature,
)
from runner.interrupts import Terminated
from runner.version import tool_version


def command_modules() -> list[ModuleType]:
    """Every module in runner.cli.commands, in name order."""
    from runner.cli import commands

    names = sorted(m.name for m in pkgutil.iter_modules(commands.__path__) if not m.name.startswith("_"))
    return [importlib.import_module(f"{commands.__name__}.{name}") for name in names]


def build_parser() -> tuple[argparse.ArgumentParser, dict[str, ModuleType]]:
    parser = argparse.ArgumentParser(
        prog="scenario",
        description="Declarative physics scenarios, checked on several physics engines with ODE semantics.",
    )
    parser.add_argument("--version", action="version", version=f"physics-scenarios {tool_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    modules = {}
    for module in command_modules():
        module.configure(sub.add_parser(module.NAME, help=module.HELP, description=module.HELP))
        modules[module.NAME] = module
    return parser, modules


def _console(stderr: bool) -> Console:
    """A console that wraps to the terminal, or to a wide page in logs and pipes (CI)."""
    probe = Console(stderr=stderr)
    return Console(stderr=stderr, highlight=False, soft_wrap=True, width=None if probe.is_terminal else 160)


def main(argv: Sequence[str] | None = None) -> int:
    out = _console(stderr=False)
    err = _console(stderr=True)
    parser, modules = build_parser()
    args = parser.parse_args(argv)
    restore = interrupts.install()
    try:
        return int(modules[args.command].execute(args, out, err))
    except ScenarioValidationError as exc:
        for issue in exc.issues:
            err.print(f"[bold red]error:[/] {escape(str(issue))}", markup=True)
        return ExitCode.BAD_INPUT
    except (ScenarioError, UnknownBackend, UnsupportedFeature) as exc:
        err.print(f"[bold red]error:[/] {escape(str(exc))}", markup=True)
        return ExitCode.BAD_INPUT
    except (BackendNotInstalled, EngineFailure) as exc:
        err.print(f"[bold red]engine failure:[/] {escape(str(exc))}", markup=True)
        return ExitCode.ENGINE_FAILURE
    except TraceError as exc:
        err.print(f"[bold red]trace error:[/] {escape(str(exc))}", markup=True)
        return ExitCode.BAD_INPUT
    except PhysicsScenariosError as exc:
        err.print(f"[bold red]error:[/] {escape(str(exc))}", markup=True)
        return ExitCode.ENGINE_FAILURE
    except Terminated:
        err.print("terminated (SIGTERM); traces written so far are finished and marked interrupted")
        return ExitCode.TERMINATED
    except KeyboardInterrupt:
        err.print("interrupted (Ctrl-C); traces written so far are finished and marked interrupted")
        return ExitCode.INTERRUPTED
    except TraceReadError as exc:
        err.print(f"[bold red]error:[/] cannot read the trace: {escape(str(exc))}", markup=True)
        return ExitCode.BAD_INPUT
    except BrokenPipeError:
        return ExitCode.OK
    finally:
        restore()


def json_default(value: Any) -> Any:
    if isinstance(value, Path):
        return str(value)
    return str(value)


def dumps(obj: Any) -> str:
    return json.dumps(obj, indent=2, default=json_default, allow_nan=False)
