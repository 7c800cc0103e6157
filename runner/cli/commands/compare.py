"""`scenario compare`: run scenarios on several backends, each run in its own process, then report.

compare = run (isolated, in parallel) + report: the report is built from the files the runs left (traces,
partial traces of crashed runs, outcome and cost files) by the same function as `scenario report`.
"""

from __future__ import annotations

import argparse
import math
import os
import threading
from pathlib import Path

from rich.console import Console

from runner.cli import options
from runner.errors import ExitCode, UsageError
from runner.language.load import LoadedScenario, load_files, parse_overrides

NAME = "compare"
HELP = "run scenarios on several backends (each in its own process) and write a comparison report"
DEFAULT_OUT = Path("traces") / "compare"
DEFAULT_TIMEOUT = 600.0


def configure(parser: argparse.ArgumentParser) -> None:
    options.add_scenario_files(parser)
    options.add_backend(parser, options.ALL)
    options.add_variant_choice(parser)
    parser.add_argument(
        "--reference", metavar="NAME",
        help="the backend the others are measured against (default: ode if compared, else the first compared "
        "backend in name order)",
    )  # fmt: skip
    parser.add_argument(
        "--out", type=Path, default=DEFAULT_OUT, metavar="DIR",
        help=f"folder for report.html/.md/.json; traces go to DIR/traces (default: {DEFAULT_OUT}/)",
    )  # fmt: skip
    parser.add_argument(
        "-j", "--jobs", type=int, default=os.cpu_count() or 1, metavar="N", help="runs at a time (default: CPUs)"
    )
    parser.add_argument(
        "--max-divergence", type=float, metavar="VALUE",
        help="fail a backend whose body positions (m) or joint positions drift further than VALUE from the reference",
    )  # fmt: skip
    parser.add_argument(
        "--timeout", type=float, default=DEFAULT_TIMEOUT, metavar="S",
        help=f"stop a run after S seconds and report it as timed out (default: {DEFAULT_TIMEOUT:g})",
    )  # fmt: skip
    options.add_overrides(parser)
    parser.add_argument(
        "--junit",
        type=Path,
        metavar="FILE",
        help="also write JUnit XML: one testcase per "
        "scenario x variant x backend (failed assertion = failure, crash or bad input = error)",
    )


def _backends(args: argparse.Namespace) -> list[str]:
    names = options.backend_names(args)
    if args.reference and args.reference not in names:  # the reference is compared too, first
        names.insert(0, options.backend_names(argparse.Namespace(backend=[args.reference], backend_default=None))[0])
    return names


def _check(args: argparse.Namespace) -> None:
    if args.jobs < 1:
        raise UsageError(f"Invalid `-j`. Expected an integer >= 1. Received: {args.jobs}")
    if not (args.timeout > 0 and math.isfinite(args.timeout)):
        raise UsageError(f"Invalid `--timeout`. Expected a positive number of seconds. Received: {args.timeout}")
    if args.max_divergence is not None and not (args.max_divergence >= 0 and math.isfinite(args.max_divergence)):
        raise UsageError(f"Invalid `--max-divergence`. Expected a number >= 0. Received: {args.max_divergence}")


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from reports.build import ReportError, write_report
    from runner.exec.isolation import IsolatedRun, run_many

    _check(args)
    backends = _backends(args)
    overrides = parse_overrides(args.set)
    cases: list[LoadedScenario] = []
    cases.extend(load_files(options.scenario_files(args.files), args.variant, args.all_variants, overrides))
    work = [(case, b) for case in cases for b in backends]
    out.print(f"comparing {len(cases)} case(s) on {', '.join(backends)}: {len(work)} runs, {args.jobs} at a time")
    lock = threading.Lock()

    def done(run: IsolatedRun) -> None:
        colour = "green" if run.label == "passed" else "red"
        with lock:
            out.print(f"  [{colour}]{run.label:<20}[/] {run.scenario} · {run.variant} · {run.backend} "
                      f"({run.wall_seconds:.1f} s)")  # fmt: skip

    runs = run_many(work, args.out / "traces", jobs=args.jobs, timeout=args.timeout, on_done=done)
    inputs = [r.trace if r.trace is not None else r.outcome_file for r in runs]
    try:
        files = write_report(
            [p for p in inputs if p is not None], args.out, reference=args.reference, max_divergence=args.max_divergence
        )
    except ReportError as exc:
        err.print(f"[bold red]error:[/] {exc}")
        return ExitCode.BAD_INPUT
    if args.junit is not None:
        _write_junit(args.junit, runs, cases)
    s = files.document["summary"]
    colour = "green" if files.passed else "red"
    out.print(f"[bold {colour}]{s['ok']}/{s['runs']} runs pass[/] (reference {files.document['reference']})")
    out.print(f"report: {files.html}  (also {files.markdown.name}, {files.json.name}; traces in {args.out / 'traces'})")
    return ExitCode.OK if files.passed else ExitCode.ASSERTION_FAILED


def _write_junit(path: Path, runs: list, cases: list[LoadedScenario]) -> None:  # noqa: ANN001 - IsolatedRun
    from runner.ci.junit import JUnitCase, from_result, suite_properties, write_junit

    by_key = {(c.model.scenario, c.variant): c for c in cases}
    items = []
    for run in runs:
        loaded = by_key.get((run.scenario, run.variant))
        if run.result is not None:
            items.append(from_result(run.result, loaded))
        else:
            items.append(
                JUnitCase(
                    run.scenario,
                    run.variant,
                    run.backend,
                    "error",
                    kind="engine-crash",
                    message=run.label,
                    text=run.message or run.label,
                    properties=suite_properties(run.backend, loaded),
                )
            )
    write_junit(path, items)
