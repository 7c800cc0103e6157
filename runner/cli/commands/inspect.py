"""`scenario inspect`: summarise a trace file (channels, duration, events, verdicts)."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from runner.errors import ExitCode

NAME = "inspect"
HELP = "summarise a trace file"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("trace", type=Path)
    parser.add_argument(
        "--recover", action="store_true", help="read a trace cut off by a crash, up to its last complete chunk"
    )


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from reports.inspect import render_inspect

    out.print(render_inspect(args.trace, recover=args.recover))
    return ExitCode.OK
