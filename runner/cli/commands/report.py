"""`scenario report`: build the comparison report (report.html/.md/.json) from trace files alone."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape

from runner.cli import options
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
    parser.add_argument("--force", action="store_true",
                        help="overwrite report files in DIR that scenario did not write (refused without it)")
    options.add_judgement(parser)


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from reports.build import ReportError, write_report
    from runner.trace.output import write_error

    if args.max_divergence is not None and not (args.max_divergence >= 0 and math.isfinite(args.max_divergence)):
        raise UsageError(f"Invalid `--max-divergence`. Expected a number >= 0. Received: {args.max_divergence}")
    try:
        files = write_report(args.traces, args.out, reference=args.reference, max_divergence=args.max_divergence,
                             require_agreement=args.require_agreement, force=args.force)  # fmt: skip
    except ReportError as exc:
        cause = exc.__cause__
        if isinstance(cause, OSError):  # a full or read-only disk is an output error (74), a bad folder bad input
            raise write_error(cause, f"the report into {args.out}") from exc
        err.print(f"[bold red]error:[/] {escape(str(exc))}")
        return ExitCode.BAD_INPUT
    print_verdict(out, files.document)
    out.print(f"report: {files.html}  (also {files.markdown.name}, {files.json.name})", markup=False)
    return ExitCode.OK if files.passed else ExitCode.ASSERTION_FAILED


def print_verdict(out: Console, doc: dict[str, Any]) -> None:
    """The report's headline on the console, and the documented cause of each departure."""
    s, h = doc["summary"], doc["headline"]
    colour = "green" if h["badge"] == "PASS" else "red"
    against = f"against {doc['reference']}" if doc["comparison"] == "reference" else "engines compared with each other"
    out.print(f"[bold {colour}]{h['badge']}[/] {s['ok']}/{s['runs']} runs pass ({escape(against)}): "
              f"{escape(h['text'])}", highlight=False)  # fmt: skip
    for d in h["agreement"]["departures"]:
        if d.get("cause"):
            out.print(f"  {escape(d['backend'])}: see {escape(d['cause']['link'])}", highlight=False)
