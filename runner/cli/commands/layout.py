"""`scenario layout`: the Foxglove layout for some scenarios (also written beside every folder of traces)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rich.console import Console

from reports.trace_format import LAYOUT_FILE
from runner.cli import options
from runner.errors import ExitCode, ScenarioError
from runner.language.load import load_files

NAME = "layout"
HELP = f"write the Foxglove layout ({LAYOUT_FILE}) for scenarios: 3D scene, asserted quantities, events, log"


def configure(parser: argparse.ArgumentParser) -> None:
    options.add_scenario_files(parser)
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help=f"write DIR/{LAYOUT_FILE} (default: print the layout)")  # fmt: skip


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.cli.layouts import layout_spec
    from runner.trace.layout import layout_text, write_layout

    cases = load_files(options.scenario_files(args.files), None, True)
    spec = layout_spec(cases)
    if args.out is None:
        sys.stdout.write(layout_text(spec))
        return ExitCode.OK
    try:
        path = write_layout(args.out, spec)
    except OSError as exc:
        raise ScenarioError(f"cannot write {args.out / LAYOUT_FILE}: {exc.strerror or exc}") from None
    err.print(f"layout: {path} (Foxglove: Layouts, Import from file)", markup=False)
    return ExitCode.OK
