"""`scenario conformance`: run the conformance suite on every backend and print the matrix."""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from rich.console import Console

from backends.registry import DEFAULT_BACKEND
from runner.cli import options
from runner.errors import ExitCode, UsageError

NAME = "conformance"
HELP = "run the conformance suite on every installed backend and print the matrix"
DEFAULT_OUT = Path("traces") / "conformance"


def configure(parser: argparse.ArgumentParser) -> None:
    options.add_backend(parser, options.ALL)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"folder for the matrix (default {DEFAULT_OUT})")
    parser.add_argument("-j", "--jobs", type=int, default=None, help="worker processes at once (default: one per core)")
    parser.add_argument(
        "--suite", type=Path, default=None, help="folder of conformance scenarios (default: the built-in suite)"
    )
    parser.add_argument(
        "--markdown", type=Path, default=None, metavar="FILE", help="also write the Markdown matrix here"
    )
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds one case may run (default 120)")
    parser.add_argument("--quiet", "-q", action="store_true", help="print the failures and the result line only")


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.conformance import (
        DEFAULT_SUITE,
        REFERENCE,
        broken,
        build_matrix,
        console,
        discover,
        markdown,
        run_suite,
    )

    if args.jobs is not None and args.jobs < 1:
        raise UsageError(f"-j expects a number of processes >= 1, found {args.jobs}")
    if args.timeout <= 0:
        raise UsageError(f"--timeout expects seconds > 0, found {args.timeout:g}")
    backends = options.backend_names(args)
    first = [b for b in (REFERENCE, DEFAULT_BACKEND) if b in backends]  # the reference's column, then the default
    backends = first + [b for b in backends if b not in first]
    suite = (args.suite or DEFAULT_SUITE).resolve()
    cases = discover(suite)
    shown = os.path.relpath(suite, Path.cwd()) if suite.is_relative_to(Path.cwd()) else str(suite)
    if suite == DEFAULT_SUITE.resolve():
        shown = "scenarios/conformance"
    err.print(f"conformance: {len(cases)} cases on {', '.join(backends)}")
    runs = run_suite(
        cases,
        backends,
        args.jobs,
        args.timeout,
        on_done=lambda r: err.print(f"  {r.backend}: done in {r.wall_seconds:.1f} s"),
    )
    matrix = build_matrix(cases, runs, shown)
    args.out.mkdir(parents=True, exist_ok=True)
    text = markdown(matrix)
    (args.out / "conformance.md").write_text(text, encoding="utf-8")
    (args.out / "conformance.json").write_text(json.dumps(matrix, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    if args.markdown is not None:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text(text, encoding="utf-8")
    console(matrix, out, quiet=args.quiet)
    out.print(f"  matrix: {args.out / 'conformance.md'}, {args.out / 'conformance.json'}", markup=False)
    if matrix["passed"]:
        return ExitCode.OK
    return ExitCode.ENGINE_FAILURE if broken(matrix) else ExitCode.ASSERTION_FAILED
