"""`scenario robots survey`: run every URDF and MJCF model under some folders on every engine, write the table."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rich.console import Console

from runner.cli import options
from runner.errors import ExitCode, UsageError

NAME = "robots"
HELP = "robot models: `survey` runs every model under folders on every engine and writes the table"


def configure(parser: argparse.ArgumentParser) -> None:
    from runner.survey.run import DEFAULT_TIMEOUT

    sub = parser.add_subparsers(dest="robots_command", required=True, metavar="SUBCOMMAND")
    survey = sub.add_parser(
        "survey",
        help="run every model (.urdf, MJCF .xml) under PATHS unmodified on a ground plane on each engine",
        description="Run every model (.urdf, MJCF .xml) found under PATHS unmodified on a ground plane under "
        "gravity on each engine, and write the table: ran / refused (the missing feature) / crashed / energy / "
        'failed. Rules: docs/robots.md, "The survey".',
    )
    survey.add_argument("paths", nargs="+", metavar="PATHS",
                        help="model files or folders (searched recursively); `@pybullet_data`: pybullet's")  # fmt: skip
    options.add_backend(survey, options.ALL)
    survey.add_argument("--out", type=Path, metavar="FILE.md", help="write the Markdown table here")
    survey.add_argument("--duration", type=float, default=2.0, metavar="S", help="simulated seconds (default 2)")
    survey.add_argument("--exclude", action="append", default=[], metavar="GLOB",
                        help="leave out models whose path matches (repeatable), e.g. 'random_urdfs/*'")  # fmt: skip
    survey.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, metavar="S",
                        help=f"wall-clock seconds one run may take (default {DEFAULT_TIMEOUT:g})")  # fmt: skip
    survey.add_argument("--target", type=float, default=None, metavar="PCT",
                        help="exit 1 when an engine runs under PCT %% of the models, or a cell crashed")  # fmt: skip
    survey.add_argument("-j", "--jobs", type=int, default=1, metavar="N", help="runs in parallel (default 1)")


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.survey.models import find_models
    from runner.survey.run import run_survey
    from runner.survey.table import CRASHED, markdown, totals_markdown

    for flag, value in (("--duration", args.duration), ("--timeout", args.timeout)):
        if not (value > 0 and math.isfinite(value)):
            raise UsageError(f"Invalid `{flag}`. Expected a positive number of seconds. Received: {value}")
    if args.jobs < 1:
        raise UsageError(f"Invalid `-j`. Expected a positive number of processes. Received: {args.jobs}")
    backends = options.backend_names(args)
    for text in args.paths:
        from runner.survey.models import resolve_root

        if not resolve_root(text).exists():
            raise UsageError(f"no file or folder at {text}")
    models = find_models(args.paths, args.exclude)
    err.print(f"survey: {len(models)} models on {', '.join(backends)}, {args.duration:g} s each")
    survey = run_survey(models, backends, args.duration, args.jobs, args.timeout,
                        on_model=lambda label: err.print(f"  {label}", highlight=False))  # fmt: skip
    text = markdown(survey)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")
        out.print(f"table: {args.out}")
    else:
        out.print(text, highlight=False, markup=False)
    out.print(totals_markdown(survey), highlight=False, markup=False)
    if args.target is not None:
        short = [b for b in backends if 100 * survey.ran_fraction(b) < args.target or survey.totals(b)[CRASHED]]
        if short:
            err.print(f"below the target of {args.target:g} % ran with no crash: {', '.join(short)}")
            return ExitCode.ASSERTION_FAILED
    return ExitCode.OK
