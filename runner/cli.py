"""The `scenario` command: a thin layer that parses arguments, calls the library and maps errors to exit codes.

Exit codes (runner.errors.ExitCode): 0 all assertions passed; 1 an assertion failed; 2 bad input (scenario,
option, path, unknown backend, unsupported feature); 3 backend or engine failure (missing engine, engine
error, NaN or blow-up); 130 interrupted (SIGINT); 143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from types import FrameType
from typing import Any

from rich.console import Console

from backends.registry import DEFAULT_BACKEND
from reports.trace_reader import TraceReadError

from .errors import (
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

DEFAULT_OUT = Path("traces")


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that traces are finished like on Ctrl-C."""


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    raise Terminated()


def build_parser() -> argparse.ArgumentParser:
    from .version import tool_version

    parser = argparse.ArgumentParser(
        prog="scenario",
        description="Declarative physics scenarios, checked on several physics engines with ODE semantics.",
    )
    parser.add_argument("--version", action="version", version=f"physics-scenarios {tool_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = sub.add_parser("run", help="run scenarios and print verdicts")
    run.add_argument("files", nargs="+", type=Path, metavar="FILE")
    run.add_argument("--backend", "-b", default=DEFAULT_BACKEND, help=f"engine to use (default {DEFAULT_BACKEND})")
    group = run.add_mutually_exclusive_group()
    group.add_argument("--variant", help="run this variant (default: the file's first variant)")
    group.add_argument("--all-variants", action="store_true", help="run every variant")
    run.add_argument("--out", type=Path, default=DEFAULT_OUT, help="folder for the traces (default: traces/)")
    run.add_argument("--no-trace", action="store_true", help="do not write traces")
    run.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a value, e.g. world.dt=0.01 or params.count=50 (repeatable)",
    )
    run.add_argument("--force", action="store_true", default=True, help=argparse.SUPPRESS)
    out = run.add_mutually_exclusive_group()
    out.add_argument("--quiet", "-q", action="store_true", help="print only failures and the summary")
    out.add_argument("--json", action="store_true", help="print the results as JSON")
    val = sub.add_parser("validate", help="check scenario files without running them")
    val.add_argument("files", nargs="+", type=Path, metavar="FILE")
    sub.add_parser("schema", help="print the JSON Schema of the scenario language")
    sub.add_parser("backends", help="list the backends, their versions and whether they are installed")
    ins = sub.add_parser("inspect", help="summarise a trace file")
    ins.add_argument("trace", type=Path)
    ins.add_argument("--recover", action="store_true", help="read a trace cut off by a crash")
    return parser


def _console(stderr: bool) -> Console:
    """A console that wraps to the terminal, or to a wide page in logs and pipes (CI)."""
    probe = Console(stderr=stderr)
    return Console(stderr=stderr, highlight=False, soft_wrap=True, width=None if probe.is_terminal else 160)


def main(argv: Sequence[str] | None = None) -> int:
    out = _console(stderr=False)
    err = _console(stderr=True)
    args = build_parser().parse_args(argv)
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        return int(_dispatch(args, out, err))
    except ScenarioValidationError as exc:
        for issue in exc.issues:
            err.print(f"[bold red]error:[/] {issue}", markup=True)
        return ExitCode.BAD_INPUT
    except (ScenarioError, UnknownBackend, UnsupportedFeature) as exc:
        err.print(f"[bold red]error:[/] {exc}", markup=True)
        return ExitCode.BAD_INPUT
    except (BackendNotInstalled, EngineFailure) as exc:
        err.print(f"[bold red]engine failure:[/] {exc}", markup=True)
        return ExitCode.ENGINE_FAILURE
    except TraceError as exc:
        err.print(f"[bold red]trace error:[/] {exc}", markup=True)
        return ExitCode.BAD_INPUT
    except PhysicsScenariosError as exc:
        err.print(f"[bold red]error:[/] {exc}", markup=True)
        return ExitCode.ENGINE_FAILURE
    except Terminated:
        err.print("terminated (SIGTERM); traces written so far are finished and marked interrupted")
        return ExitCode.TERMINATED
    except KeyboardInterrupt:
        err.print("interrupted (Ctrl-C); traces written so far are finished and marked interrupted")
        return ExitCode.INTERRUPTED
    except TraceReadError as exc:
        err.print(f"[bold red]error:[/] cannot read the trace: {exc}", markup=True)
        return ExitCode.BAD_INPUT
    except BrokenPipeError:
        return ExitCode.OK
    finally:
        signal.signal(signal.SIGTERM, previous)


def _dispatch(args: argparse.Namespace, out: Console, err: Console) -> int:
    if args.command == "run":
        from .cli_run import command_run

        return command_run(args, out, err)
    if args.command == "validate":
        return _validate(args.files, out)
    if args.command == "schema":
        from .schema import schema_text

        sys.stdout.write(schema_text())
        return ExitCode.OK
    if args.command == "backends":
        return _backends(out)
    if args.command == "inspect":
        from reports.inspect import render_inspect

        out.print(render_inspect(args.trace, recover=args.recover))
        return ExitCode.OK
    raise ScenarioError(f"unknown command {args.command}")  # pragma: no cover - argparse refuses it first


def _validate(files: list[Path], out: Console) -> int:
    from .program import build_program
    from .scenario.load import load_scenario, variant_names

    issues: list[Any] = []
    for path in files:
        try:
            names = variant_names(path)
            for name in names:
                build_program(load_scenario(path, None if name == "base" else name))
            out.print(f"ok {path} ({len(names)} case{'s' if len(names) != 1 else ''}: {', '.join(names)})")
        except ScenarioValidationError as exc:
            issues.extend(exc.issues)
    if issues:
        raise ScenarioValidationError(issues)
    return ExitCode.OK


def _backends(out: Console) -> int:
    from rich.table import Table

    from backends.registry import engine_version, is_installed, list_backends

    table = Table(title="backends")
    for col in ("name", "engine version", "installed", "description", "install"):
        table.add_column(col)
    for entry in list_backends():
        installed = is_installed(entry.name)
        table.add_row(
            entry.name + (" (default)" if entry.name == DEFAULT_BACKEND else ""),
            engine_version(entry.name),
            "yes" if installed else "no",
            entry.description,
            "" if installed else entry.hint,
        )
    out.print(table)
    return ExitCode.OK


def json_default(value: Any) -> Any:
    if isinstance(value, Path):
        return str(value)
    return str(value)


def dumps(obj: Any) -> str:
    return json.dumps(obj, indent=2, default=json_default, allow_nan=False)
