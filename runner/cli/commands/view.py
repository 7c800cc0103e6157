"""`scenario view`: a scenario live in a window (its inputs recorded with --record), or traces replayed."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from backends.registry import DEFAULT_BACKEND, entry, is_installed
from runner.cli import options
from runner.errors import BackendNotInstalled, ExitCode, UsageError

NAME = "view"
HELP = "run a scenario live in a window (keys and clicks as input events), or replay traces"
DEFAULT_OUT = Path("traces/view")


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE",
                        help="a scenario file (live), or one or more .mcap traces (replayed side by side)")  # fmt: skip
    parser.add_argument("--variant", help="the variant to run live (default: the file's first variant)")
    parser.add_argument("--backend", "-b", default=DEFAULT_BACKEND, help=f"engine (default {DEFAULT_BACKEND})")
    parser.add_argument("--record", metavar="NEW_VARIANT",
                        help="on closing the window, write the inputs played into FILE as a new variant")  # fmt: skip
    options.add_overrides(parser)
    parser.add_argument("--speed", type=float, default=1.0,
                        help="simulated seconds per wall-clock second (default 1; F5/F6 change it)")  # fmt: skip
    parser.add_argument("--paused", action="store_true",
                        help="start paused (F3 runs, F4 steps); a replay otherwise opens playing")  # fmt: skip
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help=f"folder for the live run's trace (default {DEFAULT_OUT}/; overwritten)")  # fmt: skip
    parser.add_argument("--at", type=float, default=0.0, metavar="T", help="replay: start at simulated time T")
    parser.add_argument("--camera", choices=("lab", "auto"), default=None,
                        help="lab: the seed's, (1,-8,5) pitch -25 (default live); auto: framing the bodies "
                             "(default replaying)")  # fmt: skip
    parser.add_argument("--script", type=Path, metavar="FILE",
                        help="timed inputs, screenshots and closing from a YAML file (docs/view.md)")  # fmt: skip
    parser.add_argument("--offscreen", action="store_true",
                        help="draw offscreen (software renderer): no display needed; use with --script")  # fmt: skip


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.view.script import load_script

    if not args.speed > 0:
        raise UsageError(f"Invalid `--speed`. Expected a positive number. Received: {args.speed}")
    script = load_script(args.script) if args.script else []
    traces = [f for f in args.files if f.suffix == ".mcap"]
    if traces:
        if len(traces) != len(args.files):
            raise UsageError("give either one scenario file or .mcap traces, not both")
        if args.record or args.variant or args.set:
            raise UsageError("--record, --variant and --set apply to a scenario file, not to traces")
        from runner.view.app import view_traces

        where = view_traces(traces, at=args.at, paused=args.paused, speed=args.speed, offscreen=args.offscreen,
                            script=script, camera=args.camera or "auto")  # fmt: skip
        out.print(where, highlight=False)
        return ExitCode.OK
    if len(args.files) != 1:
        raise UsageError("`scenario view` runs one scenario file at a time")
    return _live(args, out, err, script)


def _live(args: argparse.Namespace, out: Console, err: Console, script: list) -> int:  # noqa: ANN001
    from runner.ci.render import verdict_table
    from runner.language.load import load_all, parse_overrides
    from runner.view.app import view_scenario

    entry(args.backend)  # an unknown name is bad input (exit 2)
    if not is_installed(args.backend):
        hint = entry(args.backend).hint
        raise BackendNotInstalled(f"Backend `{args.backend}` is not installed. Install it with: {hint}")
    (loaded,) = load_all(args.files[0], args.variant, False, parse_overrides(args.set))
    outcome = view_scenario(loaded, args.backend, args.out, record=args.record, speed=args.speed, paused=args.paused,
                            offscreen=args.offscreen, script=script, camera=args.camera or "lab")  # fmt: skip
    for warning in outcome.warnings:
        err.print(f"[yellow]warning:[/] {escape(warning)}", markup=True)
    result = outcome.result
    out.print(verdict_table(result))
    if result.trace:
        out.print(f"trace: {escape(result.trace)}")
    if args.record:
        out.print(f"recorded variant `{escape(args.record)}` into {escape(str(args.files[0]))}:")
        out.print(outcome.recorded.rstrip(), markup=False, highlight=False)
    if result.status == "engine-failure":
        err.print(f"[bold red]engine failure:[/] {escape(result.failure or '')}", markup=True)
        return ExitCode.ENGINE_FAILURE
    return ExitCode.OK if result.passed else ExitCode.ASSERTION_FAILED
