"""The `scenario` command: a thin layer that parses arguments, calls the library and maps errors to exit codes.

Exit codes (runner.errors.ExitCode, mapped in one place: runner.exec.exits): 0 all assertions passed; 1 an
assertion failed; 2 bad input (scenario, option, path, unknown backend, unsupported feature, an output
another run is writing or that scenario did not write); 3 backend or engine failure (missing engine,
engine error, NaN or blow-up, a crash by a signal, a time-out); 70 a bug in this tool ("internal error,
please report"; a traceback with SCENARIO_DEBUG=1); 74 an output could not be written (disk full, I/O
error); 130 interrupted (SIGINT); 143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import importlib
import json
import pkgutil
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from rich.console import Console
from rich.markup import escape

from runner import interrupts
from runner.errors import ExitCode, ScenarioValidationError
from runner.exec.exits import classify
from runner.interrupts import Terminated
from runner.startup import imports_uncollected
from runner.version import tool_version


def command_names() -> list[str]:
    """Every command, in name order: the modules of runner.cli.commands (listed, not imported)."""
    from runner.cli import commands

    return sorted(m.name for m in pkgutil.iter_modules(commands.__path__) if not m.name.startswith("_"))


def command_modules(only: str | None = None) -> list[ModuleType]:
    """Every module in runner.cli.commands, in name order (``only``: that command's alone)."""
    from runner.cli import commands

    names = [only] if only is not None else command_names()
    return [importlib.import_module(f"{commands.__name__}.{name}") for name in names]


def chosen_command(argv: Sequence[str] | None) -> str | None:
    """The command the arguments name, when it comes before any option (``scenario run ...``), so that only
    its module is imported (each command imports what it needs: reports, rich tables, engines); None when
    the whole parser is needed (no command, a misspelt one, ``--help`` or ``--version``)."""
    args = sys.argv[1:] if argv is None else list(argv)
    if not args or args[0] not in command_names():
        return None
    return args[0]


def build_parser(argv: Sequence[str] | None = None) -> tuple[argparse.ArgumentParser, dict[str, ModuleType]]:
    """The parser; with ``argv`` naming a command, one that knows only that command (the same parsing and
    messages for it, without importing the others)."""
    parser = argparse.ArgumentParser(
        prog="scenario",
        description="Declarative physics scenarios, checked on several physics engines with ODE semantics.",
    )
    parser.add_argument("--version", action="version", version=f"physics-scenarios {tool_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    modules = {}
    for module in command_modules(chosen_command(argv) if argv is not None else None):
        module.configure(sub.add_parser(module.NAME, help=module.HELP, description=module.HELP))
        modules[module.NAME] = module
    return parser, modules


def _console(stderr: bool) -> Console:
    """A console that wraps to the terminal, or to a wide page in logs and pipes (CI). Emoji codes are off:
    text from a scenario or a location (`file.yaml:100:1`) holds `:100:`, which rich would print as an emoji;
    markup in such text is escaped where it is printed (``rich.markup.escape``)."""
    probe = Console(stderr=stderr)
    width = None if probe.is_terminal else 160
    return Console(stderr=stderr, highlight=False, soft_wrap=True, width=width, emoji=False)


def main(argv: Sequence[str] | None = None) -> int:
    restore = interrupts.install()  # first: a signal while the commands are imported is an interruption too
    err: Console | None = None
    try:
        out = _console(stderr=False)
        err = _console(stderr=True)
        argv = sys.argv[1:] if argv is None else list(argv)
        with imports_uncollected():  # the command's modules: long-lived objects only
            parser, modules = build_parser(argv)
        args = parser.parse_args(argv)
        return int(modules[args.command].execute(args, out, err))
    except BrokenPipeError:  # our output was closed (`scenario ... | head`): nothing more to say
        return ExitCode.OK
    except BaseException as exc:  # noqa: BLE001 - the one place where the exception tree meets exit codes
        return _report(exc, err or _console(stderr=True))
    finally:
        restore()


def _report(exc: BaseException, err: Console) -> int:
    """Print ``exc`` as its first message line (runner.exec.exits) and give its exit code. A bug is
    "internal error, please report" (exit 70), with its traceback when SCENARIO_DEBUG=1; in the test
    suite it is raised."""
    if isinstance(exc, SystemExit | GeneratorExit):
        raise exc
    exit = classify(exc)
    if exit.code in (ExitCode.INTERRUPTED, ExitCode.TERMINATED):
        exc = Terminated() if exit.code is ExitCode.TERMINATED else KeyboardInterrupt()  # whatever wrapped it
    if isinstance(exc, KeyboardInterrupt):  # before importing anything: the signal may have cut an import short,
        signal = "SIGTERM" if isinstance(exc, Terminated) else "Ctrl-C"  # leaving that module half made
        err.print(f"{exit.label} ({signal}); {exit.message}", markup=False)
        return exit.code
    from runner.cli.outcomes import debug, in_tests  # with the verdict tables: not every command prints them

    remote = getattr(exc, "remote_traceback", "")
    if exit.code is ExitCode.INTERNAL_ERROR and in_tests():  # a bug fails the test that met it, with its traceback
        if remote:
            exc.add_note(f"raised in a worker process:\n{remote}")
        raise exc
    issues = getattr(exc, "issues", None)
    if isinstance(exc, ScenarioValidationError) and issues:
        for issue in issues:
            err.print(f"[bold red]{exit.label}:[/] {escape(str(issue))}", markup=True)
    else:
        err.print(f"[bold red]{escape(exit.label)}:[/] {escape(exit.message)}", markup=True)
    if exit.code is ExitCode.INTERNAL_ERROR:
        if debug():
            err.print(escape(remote or "".join(traceback.format_exception(exc))), highlight=False)
        else:
            err.print("run again with SCENARIO_DEBUG=1 to see where it happened, and please report it")
    return exit.code


def json_default(value: Any) -> Any:
    if isinstance(value, Path):
        return str(value)
    return str(value)


def dumps(obj: Any) -> str:
    return json.dumps(obj, indent=2, default=json_default, allow_nan=False)
