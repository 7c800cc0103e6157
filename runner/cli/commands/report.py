"""`scenario report`: build the comparison report (report.html/.md/.json) from trace files alone."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from runner.errors import ExitCode, UsageError

NAME = "report"
HELP = "build a comparison report from traces (files or folders)"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "traces", nargs="+", type=Path, metavar="TRACE",
        help=".mcap traces, .mcap.partial traces of crashed runs, their .outcome.json/.cost.json files, or folders",
    )  # fmt: skip
    parser.add_argument(
        "--out", type=Path, required=True, metavar="DIR", help="folder for report.html, report.md and report.json"
    )
    parser.add_argument(
        "--reference", metavar="NAME",
        help="the backend the others are measured against (default: ode if present, else the first backend in name "
        "order)",
    )  # fmt: skip
    parser.add_argument(
        "--max-divergence", type=float, metavar="VALUE",
        help="fail a backend whose positions (m: bodies, sliders, joint drift) stray further than VALUE from their "
        "truth (the reference backend where no truth is known); also the report's position threshold",
    )  # fmt: skip


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from reports.build import ReportError, write_report

    if args.max_divergence is not None and not (args.max_divergence >= 0 and math.isfinite(args.max_divergence)):
        raise UsageError(f"Invalid `--max-divergence`. Expected a number >= 0. Received: {args.max_divergence}")
    try:
        files = write_report(args.traces, args.out, reference=args.reference, max_divergence=args.max_divergence)
    except ReportError as exc:
        err.print(f"[bold red]error:[/] {escape(str(exc))}")
        return ExitCode.BAD_INPUT
    s, h = files.document["summary"], files.document["headline"]
    colour = "green" if files.passed else "red"
    out.print(f"[bold {colour}]{s['ok']}/{s['runs']} runs pass[/] (reference {escape(files.document['reference'])}): "
              f"{escape(h['badge'])}, {escape(h['text'])}")  # fmt: skip
    out.print(f"report: {files.html}  (also {files.markdown.name}, {files.json.name})", markup=False)
    return ExitCode.OK if files.passed else ExitCode.ASSERTION_FAILED
