"""`scenario validate`: check scenario files (every variant) without running them.

It refuses exactly what `scenario run` would refuse before the first step: the same loading and compiling
(with `--set`), and the capabilities and options of the backends asked for (`--backend`, default the same as
`run`'s), so that a file that validates does not then fail to start.
"""

from __future__ import annotations

import argparse
from typing import Any

from rich.console import Console
from rich.markup import escape

from backends.registry import DEFAULT_BACKEND
from runner.cli import options
from runner.errors import ExitCode, ScenarioValidationError

NAME = "validate"
HELP = "check scenario files without running them"


def configure(parser: argparse.ArgumentParser) -> None:
    options.add_scenario_files(parser)
    options.add_backend(parser, DEFAULT_BACKEND)
    options.add_variant_choice(parser, default_text="every variant")
    options.add_overrides(parser)


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from backends.registry import check_capabilities, get_backend
    from runner.compile.program import build_program
    from runner.language.load import BASE_CASE, load_scenario, parse_overrides, variant_names

    backends = [get_backend(name) for name in options.backend_names(args)]
    overrides = parse_overrides(args.set)
    issues: list[Any] = []
    for path in options.scenario_files(args.files):
        try:
            names = [args.variant] if args.variant else variant_names(path)
            for name in names:
                program = build_program(load_scenario(path, None if name == BASE_CASE else name, overrides))
                for cls in backends:
                    check_capabilities(cls, program.world)
            cases = f"{len(names)} case{'s' if len(names) != 1 else ''}: {', '.join(names)}"
            out.print(f"ok {escape(str(path))} ({cases})")
        except ScenarioValidationError as exc:
            issues.extend(exc.issues)
    if issues:
        raise ScenarioValidationError(issues)
    return ExitCode.OK
