"""`scenario validate`: check scenario files (every variant) without running them."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape

from runner.errors import ExitCode, ScenarioValidationError

NAME = "validate"
HELP = "check scenario files without running them"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE")


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.compile.program import build_program
    from runner.language.load import BASE_CASE, load_scenario, variant_names

    issues: list[Any] = []
    for path in args.files:
        try:
            names = variant_names(path)
            for name in names:
                build_program(load_scenario(path, None if name == BASE_CASE else name))
            out.print(f"ok {escape(str(path))} ({len(names)} case{'s' if len(names) != 1 else ''}: {', '.join(names)})")
        except ScenarioValidationError as exc:
            issues.extend(exc.issues)
    if issues:
        raise ScenarioValidationError(issues)
    return ExitCode.OK
