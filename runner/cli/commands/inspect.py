"""`scenario inspect`: summarise a trace file (channels, duration, events, verdicts), or a scenario file's
robots (links, joints, limits, actuators, as their model files say)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from rich.console import Console

from runner.errors import ExitCode, UsageError

NAME = "inspect"
HELP = "summarise a trace file, or a scenario file's robots"
_SCENARIO_SUFFIXES = (".yaml", ".yml")


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "trace", type=Path, metavar="TRACE|SCENARIO",
        help="a trace (.mcap), or a scenario (.yaml): its robots' links, joints and actuators",
    )  # fmt: skip
    parser.add_argument(
        "--recover", action="store_true", help="read a trace cut off by a crash, up to its last complete chunk"
    )
    parser.add_argument("--variant", metavar="NAME", help="a scenario's variant (default: the file's first)")
    parser.add_argument("--json", action="store_true", help="a scenario's robots as JSON")


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    if args.trace.suffix.lower() in _SCENARIO_SUFFIXES:
        return _scenario(args, out)
    if args.json or args.variant:
        raise UsageError("--json and --variant are for a scenario file (.yaml); a trace's summary is text")
    from reports.inspect import render_inspect

    out.print(render_inspect(args.trace, recover=args.recover))
    return ExitCode.OK


def _scenario(args: argparse.Namespace, out: Console) -> int:
    from runner.cli.inspect_scenario import robots_data, robots_summary
    from runner.language.load import load_scenario

    if args.recover:
        raise UsageError("--recover is for a trace (.mcap)")
    data = robots_data(load_scenario(args.trace, args.variant))
    if args.json:
        out.print_json(json.dumps(data, ensure_ascii=False))
    else:
        out.print(robots_summary(data))
    return ExitCode.OK
