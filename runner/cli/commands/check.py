"""`scenario check`: run cases and compare them with their golden files (see `scenario baseline`).

The cases run through ``runner.exec`` as `scenario run` runs them, so a case that does not complete ends with
the exit code and first line `run` gives; one that completes is compared with its golden file. The command
exits with the most severe of its cases' codes (runner.exec.exits.most_severe).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console
from rich.markup import escape

from runner.cli import options
from runner.cli.commands.baseline import add_case_options, load_cases, sit_out_refused

if TYPE_CHECKING:
    from runner.ci.regression import CaseOutcome

NAME = "check"
HELP = "run scenarios and compare them with their recorded baselines"


def configure(parser: argparse.ArgumentParser) -> None:
    from runner.exec.executors import add_arguments

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
    add_arguments(parser)


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.ci.regression import PASSED, check_cases, golden_path, parse_tolerance_options
    from runner.cli.outcomes import case_line
    from runner.errors import ScenarioError
    from runner.exec.executors import make_executor
    from runner.exec.exits import most_severe

    overrides = parse_tolerance_options(args.atol, args.rtol)
    backends = options.backend_names(args)
    cases = load_cases(args.files, args.variant, args.set)
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ScenarioError(f"cannot use {args.out} as the trace folder: {exc.strerror or exc}") from None
    executor = make_executor(args.executor, args.jobs, args.ray_address)
    try:
        pairs = [(case, backend) for backend in backends for case in cases]
        if options.asks_every_engine(args):  # `scenario baseline --backend all` records none for a refused case;
            # a refused case that has a golden file is a regression and runs (its refusal is the error)
            pairs = sit_out_refused(pairs, out, "checked", lambda case, b: golden_path(args.baseline, case, b).exists())
        outcomes = check_cases(pairs, args.baseline, args.out, overrides, executor,
                               lambda o: _print(out, err, o, args.quiet))  # fmt: skip
    finally:
        executor.close()
    _stale(err, args.baseline, cases, backends, args.variant)
    if args.junit:
        from runner.ci.junit import from_outcome, write_junit

        write_junit(args.junit, [from_outcome(o) for o in outcomes])
    passed = sum(o.outcome == PASSED for o in outcomes)
    colour = "green" if passed == len(outcomes) else "red"
    out.print(f"[bold {colour}]{passed}/{len(outcomes)} cases match their baselines and pass[/]")
    for o in outcomes:  # the same lines as `run`'s summary
        names = (o.loaded.model.scenario, o.loaded.variant, o.backend)
        if o.outcome != PASSED:
            out.print(case_line(*names, o.exit.headline))
        elif o.exit.code == 0:
            from runner.ci.render import known_limit_lines

            for text in known_limit_lines(o.result):
                out.print(f"  {' · '.join(map(escape, names))}: [yellow]{escape(text)}[/]", highlight=False)
    code = most_severe(o.exit.code for o in outcomes)
    if any(o.run.trace is not None for o in outcomes):
        from runner.cli.layouts import leave_layout

        return leave_layout(err, [args.out], cases, code)  # foxglove-layout.json beside the traces
    return code


def _print(out: Console, err: Console, outcome: CaseOutcome, quiet: bool) -> None:
    """One case as it ends: what stopped it (stderr, as `run` prints it), or how it compares."""
    from runner.ci.regression import PASSED, comparison_lines
    from runner.ci.render import verdict_text
    from runner.cli.outcomes import print_problem, print_result

    label = escape(outcome.label)
    result = outcome.result
    if result is None:
        print_problem(err, outcome.run)
        return
    if outcome.run.output.strip():
        err.print(escape(outcome.run.output.rstrip()), highlight=False)  # what the engine printed
    if result.status == "engine-failure":
        print_result(out, result, quiet)
        return
    comparison = outcome.comparison
    if outcome.problem:
        out.print(f"[bold red]error[/] {label}: {escape(outcome.problem)}")
    elif outcome.outcome == PASSED:
        if not quiet:
            out.print(f"[green]ok[/] {label} matches {escape(str(outcome.golden))}")
    elif outcome.diverges:
        out.print(f"[bold red]DIVERGES[/] {label} from {escape(str(outcome.golden))}")
    else:
        out.print(f"[bold red]FAIL[/] {label}: matches its baseline, but assertions fail")
    if comparison is not None and (not quiet or outcome.outcome != PASSED):
        for line in comparison_lines(comparison, outcome.plot):
            out.print(f"  {escape(line)}")
    if not result.passed:
        out.print(verdict_text(result, failures_only=True), markup=False, end="")


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
