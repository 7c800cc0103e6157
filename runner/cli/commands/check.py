"""`scenario check`: run cases and compare them with their golden files (see `scenario baseline`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from runner.cli import options
from runner.cli.commands.baseline import add_case_options, load_cases

NAME = "check"
HELP = "run scenarios and compare them with their recorded baselines"


def configure(parser: argparse.ArgumentParser) -> None:
    add_case_options(parser)
    parser.add_argument(
        "--out", type=Path, default=Path("traces"), help="folder for traces and divergence plots (default traces/)"
    )
    parser.add_argument("--junit", type=Path, metavar="FILE", help="also write a JUnit XML report to FILE")
    parser.add_argument(
        "--atol",
        action="append",
        default=[],
        metavar="[FIELD=]X",
        help="absolute tolerance for every field, or for one (pos, quat, vel, angvel, position, velocity, "
        "motor_force, state, event; or NAME.FIELD, e.g. box.pos); repeatable; beats the golden file's",
    )
    parser.add_argument(
        "--rtol", action="append", default=[], metavar="[FIELD=]X", help="relative tolerance, as --atol"
    )
    parser.add_argument("--quiet", "-q", action="store_true", help="print only what diverges or fails")


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.ci.regression import ERROR, PASSED, check_case, parse_tolerance_options, verdict_text
    from runner.errors import ExitCode

    overrides = parse_tolerance_options(args.atol, args.rtol)
    backends = options.backend_names(args)
    cases = load_cases(args.files, args.variant, args.set)
    outcomes = []
    for backend in backends:
        for case in cases:
            outcome = check_case(case, backend, args.baseline, args.out, overrides)
            outcomes.append(outcome)
            _print(out, outcome, args.quiet)
            if outcome.outcome != PASSED and outcome.result is not None and not outcome.result.passed:
                out.print(verdict_text(outcome.result, failures_only=True), markup=False, end="")
    _stale(err, args.baseline, cases, backends, args.variant)
    if args.junit:
        from runner.ci.junit import from_outcome, write_junit

        write_junit(args.junit, [from_outcome(o) for o in outcomes])
    passed = sum(o.outcome == PASSED for o in outcomes)
    colour = "green" if passed == len(outcomes) else "red"
    out.print(f"[bold {colour}]{passed}/{len(outcomes)} cases match their baselines and pass[/]")
    if any(o.error_kind == "engine-failure" for o in outcomes):
        code = ExitCode.ENGINE_FAILURE
    elif any(o.outcome == ERROR for o in outcomes):
        code = ExitCode.BAD_INPUT
    else:
        code = ExitCode.OK if passed == len(outcomes) else ExitCode.ASSERTION_FAILED
    if args.out is not None and outcomes:
        from runner.cli.layouts import leave_layout

        return leave_layout(err, [args.out], cases, code)  # foxglove-layout.json beside the traces
    return code


def _print(out: Console, outcome, quiet: bool) -> None:  # noqa: ANN001 - CaseOutcome
    from runner.ci.regression import ERROR, PASSED, comparison_lines

    label = escape(outcome.label)
    if outcome.outcome == ERROR:
        out.print(f"[bold red]error[/] {label}: {escape(outcome.error)}")
        return
    comparison = outcome.comparison
    if outcome.outcome == PASSED:
        if not quiet:
            out.print(f"[green]ok[/] {label} matches {escape(str(outcome.golden))}")
    elif comparison is not None and not comparison.ok:
        out.print(f"[bold red]DIVERGES[/] {label} from {escape(str(outcome.golden))}")
    else:
        out.print(f"[bold red]FAIL[/] {label}: matches its baseline, but assertions fail")
    if comparison is not None and (not quiet or outcome.outcome != PASSED):
        for line in comparison_lines(comparison, outcome.plot):
            out.print(f"  {escape(line)}")


def _stale(err: Console, directory: Path, cases: list, backends: list[str], variant: str | None) -> None:
    """Warn about golden files of these scenarios that no case checked (a renamed or removed variant)."""
    from runner.ci.regression import golden_path

    if variant is not None or not directory.is_dir():
        return
    checked = {golden_path(directory, c, b).name for c in cases for b in backends}
    prefixes = {f"{c.model.scenario}__" for c in cases}
    for path in sorted(directory.glob("*.golden")):
        backend = path.name.removesuffix(".golden").rsplit("__", 1)[-1]
        if backend in backends and any(path.name.startswith(p) for p in prefixes) and path.name not in checked:
            err.print(f"[yellow]warning:[/] {path} has no case any more (a renamed or removed variant?)")
