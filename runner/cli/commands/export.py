"""`scenario export TRACE... --to rerun`: a trace as a native Rerun recording (``.rrd``)."""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from runner.errors import ExitCode, OutputError, ScenarioError, UsageError

NAME = "export"
HELP = "convert traces for other viewers: --to rerun writes a Rerun recording (.rrd) beside each trace"
FORMATS = ("rerun",)
RRD_SUFFIX = ".rrd"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("traces", nargs="+", type=Path, metavar="TRACE", help="trace files (.mcap)")
    parser.add_argument("--to", required=True, choices=FORMATS, help="the format to write (rerun: a .rrd file)")
    parser.add_argument("--out", type=Path, default=None, metavar="FILE",
                        help="the file to write (one trace only; default: the trace's name with .rrd)")  # fmt: skip


def rrd_path(trace: Path) -> Path:
    """Where a trace's recording goes by default: beside it, ``<trace name>.rrd``."""
    return trace.with_suffix(RRD_SUFFIX)


def export_rrds(pairs: Iterable[tuple[Path, Path]], err: Console) -> None:
    """Write each (trace, .rrd) pair and say where; the asserted quantities a recording cannot plot (a text
    state variable, a body's energy) are named. A missing rerun-sdk is bad input (exit 2, the extra to
    install); a file that cannot be written an :class:`~runner.errors.OutputError` (exit 74)."""
    from reports.rerun_export import RerunExportError, export_rerun

    for trace, out in pairs:
        try:
            path, missing = export_rerun(trace, out)
        except RerunExportError as exc:
            if "not installed" in str(exc):
                raise ScenarioError(f"--rerun / export --to rerun: {exc}") from None
            raise OutputError(str(exc)) from None
        note = f" (not plotted: {', '.join(missing)})" if missing else ""
        err.print(f"rerun: {escape(str(path))}{escape(note)}", highlight=False)


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    if args.out is not None and len(args.traces) > 1:
        raise UsageError(f"`--out FILE` names one recording; {len(args.traces)} traces were given (leave --out out)")
    export_rrds([(t, args.out if args.out is not None else rrd_path(t)) for t in args.traces], err)
    return ExitCode.OK
