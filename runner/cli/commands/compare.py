"""`scenario compare`: run scenarios on several backends, each backend in its own processes, then report.

compare = run (in worker processes, in parallel: runner.exec) + report: the report is built from the files
the runs left (traces, partial traces of crashed runs, outcome and cost files) by the same function as
`scenario report`. Each row says what `scenario run` says for the same case (runner.exec.exits); the
command's own exit code follows the report's headline: 0 when every backend passes every assertion, 1
otherwise (and when the engines disagree only with --require-agreement, beyond --max-divergence only with
that option), 2 for bad input found before anything ran.
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape

from runner.cli import options
from runner.errors import ExitCode, TraceError, UsageError
from runner.exec.cases import Case, CaseResult
from runner.language.load import BASE_CASE, LoadedScenario, load_files, parse_overrides

NAME = "compare"
HELP = "run scenarios on several backends (each in its own process) and write a comparison report"
DEFAULT_OUT = Path("traces") / "compare"
DEFAULT_TIMEOUT = 600.0


def configure(parser: argparse.ArgumentParser) -> None:
    options.add_scenario_files(parser)
    options.add_backend(parser, options.ALL)
    options.add_variant_choice(parser)
    parser.add_argument(
        "--out", type=Path, default=DEFAULT_OUT, metavar="DIR",
        help=f"folder for report.html/.md/.json; traces go to DIR/traces (default: {DEFAULT_OUT}/)",
    )  # fmt: skip
    parser.add_argument(
        "-j", "--jobs", type=int, default=os.cpu_count() or 1, metavar="N", help="runs at a time (default: CPUs)"
    )
    options.add_judgement(parser)
    parser.add_argument(
        "--timeout", type=float, default=None, metavar="S",
        help="stop a run after S seconds and report it as timed out (default: the scenario's world.budget, "
        f"else {DEFAULT_TIMEOUT:g})",
    )  # fmt: skip
    parser.add_argument("--force", action="store_true",
                        help="also overwrite files under the outputs' names that scenario did not write")  # fmt: skip
    options.add_overrides(parser)
    parser.add_argument(
        "--imports-only", action="store_true",
        help="show how each engine imported the scenario's robots (built, not stepped) and stop",
    )  # fmt: skip
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


def _runnable(work: list[tuple[LoadedScenario, str]], out: Console) -> list[tuple[LoadedScenario, str]]:
    """The (case, engine) pairs whose engine accepts the case (what `scenario validate --backend` checks); the
    others are named, with the refusal's reason, and left out of the comparison. Only when the engines were not
    named: an engine the user names that refuses a case is an error row, as in `scenario run`."""
    from backends.errors import UnsupportedFeature
    from backends.registry import check_capabilities, get_backend
    from runner.compile.program import build_program

    kept = []
    worlds: dict[int, object] = {}
    for loaded, backend in work:
        world = worlds.setdefault(id(loaded), build_program(loaded).world)
        try:
            check_capabilities(get_backend(backend), world)  # type: ignore[arg-type]
        except UnsupportedFeature as refusal:
            needs = ", ".join(sorted(str(getattr(c, "value", c)) for c in refusal.missing)) or str(refusal)
            out.print(f"not compared: {loaded.model.scenario} · {loaded.variant} on {backend}, which refuses it up "
                      f"front ({needs}; name the engines with --backend to see the refusal as an error)",
                      markup=False, highlight=False)  # fmt: skip
            continue
        kept.append((loaded, backend))
    return kept


def _check(args: argparse.Namespace) -> None:
    if args.jobs < 1:
        raise UsageError(f"Invalid `-j`. Expected an integer >= 1. Received: {args.jobs}")
    if args.timeout is not None and not (args.timeout > 0 and math.isfinite(args.timeout)):
        raise UsageError(f"Invalid `--timeout`. Expected a positive number of seconds. Received: {args.timeout}")
    if args.max_divergence is not None and not (args.max_divergence >= 0 and math.isfinite(args.max_divergence)):
        raise UsageError(f"Invalid `--max-divergence`. Expected a number >= 0. Received: {args.max_divergence}")


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from reports.build import ReportError, write_report
    from runner.cli.commands.report import print_verdict
    from runner.cli.outcomes import known_limits, print_problem
    from runner.exec.executors import LocalExecutor, check_outputs
    from runner.trace.output import write_error

    _check(args)
    backends = _backends(args)
    overrides = parse_overrides(args.set)
    cases: list[LoadedScenario] = []
    cases.extend(load_files(options.scenario_files(args.files), args.variant, args.all_variants, overrides))
    work = [(case, b) for case in cases for b in backends]
    if args.backend is None:  # every installed engine by default: those that refuse a case up front sit it out
        work = _runnable(work, out)
    if any(loaded.robots for loaded in cases):
        _show_imports(args, out, [loaded for loaded in cases if loaded.robots], backends)
        if args.imports_only:
            return ExitCode.OK
    elif args.imports_only:
        raise UsageError("`--imports-only` needs a scenario with robots (URDF or MJCF models)")
    jobs = [_case(args, loaded, b, overrides) for loaded, b in work]
    check_outputs(jobs, args.force)
    _check_reports(args.out, args.force)
    out.print(f"comparing {len(cases)} case(s) on {', '.join(backends)}: {len(work)} runs, {args.jobs} at a time",
              markup=False)  # fmt: skip

    def done(index: int, res: CaseResult) -> None:
        loaded = work[index][0]
        colour = "green" if res.passed else "red"
        where = f"{escape(loaded.model.scenario)} · {escape(loaded.variant)} · {escape(res.case.backend)}"
        out.print(f"  [{colour}]{escape(res.label):<20}[/] {where} ({res.wall_seconds:.1f} s)")
        if not res.passed:
            out.print(f"      {escape(res.headline)} {escape(f'[exit {int(res.exit.code)}]')}", highlight=False)
        for text in known_limits(res):
            out.print(f"      [yellow]{escape(text)}[/] {escape(f'[exit {int(res.exit.code)}]')}", highlight=False)
        if res.result is None:
            print_problem(err, res)

    runs = LocalExecutor(args.jobs, force=args.force).run(jobs, done)
    if any(r.trace is not None for r in runs):
        from runner.cli.layouts import write_layouts

        write_layouts([args.out / "traces"], cases)  # foxglove-layout.json beside the traces (the report links it)
    inputs = [Path(r.trace) if r.trace is not None else Path(r.outcome_file) if r.outcome_file else None for r in runs]
    if all(p is None for p in inputs) and any(r.exit.code is ExitCode.OUTPUT_ERROR for r in runs):
        # a read-only or full --out: no run could write anything, nor can the report (it was exit 2, "no traces")
        err.print(f"[bold red]output error:[/] no report: nothing could be written into {escape(str(args.out))}")
        return ExitCode.OUTPUT_ERROR
    try:
        files = write_report([p for p in inputs if p is not None], args.out, reference=args.reference,
                             max_divergence=args.max_divergence, require_agreement=args.require_agreement,
                             force=args.force)  # fmt: skip
    except ReportError as exc:
        cause = exc.__cause__
        if isinstance(cause, OSError):  # a full disk is an output error (74), a bad folder bad input (2)
            raise write_error(cause, f"the report into {args.out}") from exc
        err.print(f"[bold red]error:[/] {escape(str(exc))}")
        return ExitCode.BAD_INPUT
    if args.junit is not None:
        _write_junit(args.junit, runs, [loaded for loaded, _ in work])
    print_verdict(out, files.document)
    out.print(f"report: {files.html}  (also {files.markdown.name}, {files.json.name}; traces in {args.out / 'traces'})",
              markup=False)  # fmt: skip
    return ExitCode.OK if files.passed else ExitCode.ASSERTION_FAILED


def _case(args: argparse.Namespace, loaded: LoadedScenario, backend: str,
          overrides: tuple[tuple[str, Any], ...]) -> Case:  # fmt: skip
    from runner.exec.executors import estimate_cost
    from runner.sim.run import trace_path

    traces = args.out / "traces"
    budget = args.timeout if args.timeout is not None else (loaded.model.world.budget or DEFAULT_TIMEOUT)
    return Case(
        str(loaded.path), None if loaded.variant == BASE_CASE else loaded.variant, backend, overrides, str(traces),
        cost=estimate_cost(loaded), budget=budget, sha256=loaded.sha256,
        trace=str(trace_path(traces, loaded, backend)), scenario=loaded.model.scenario, loaded=loaded,
    )  # fmt: skip


def _show_imports(args: argparse.Namespace, out: Console, cases: list[LoadedScenario], backends: list[str]) -> None:
    """Before any run: every engine builds each robot case's world in a worker (runner.exec.imports) and the
    import tables are printed, and kept beside the traces for the report (reports.imports)."""
    from reports.imports import imports_path, is_own_imports, write_imports
    from reports.imports_render import terminal_lines
    from runner.exec.imports import file_digits, read_imports
    from runner.trace.output import write_error

    work = [(loaded, b) for loaded in cases for b in backends]
    reads = read_imports([Case(str(loaded.path), None if loaded.variant == BASE_CASE else loaded.variant, b,
                               loaded.overrides, loaded=loaded) for loaded, b in work], args.jobs)  # fmt: skip
    sections = []
    for k, loaded in enumerate(cases):
        section = {"scenario": loaded.model.scenario, "variant": loaded.variant,
                   "digits": file_digits([desc.file for desc in loaded.robots.values()]),
                   "reads": reads[k * len(backends):(k + 1) * len(backends)]}  # fmt: skip
        sections.append(section)
        for line in terminal_lines(section):
            out.print(line, markup=False, highlight=False)
    if args.imports_only:
        return
    traces = args.out / "traces"
    target = imports_path(traces)
    if target.exists() and not args.force and not is_own_imports(target):
        raise TraceError(f"{target} exists and was not written by this tool; use --force to replace it")
    try:
        write_imports(traces, sections)
    except OSError as exc:
        raise write_error(exc, str(target)) from exc


def _check_reports(out: Path, force: bool) -> None:
    """The report files a comparison replaces must be its own (or --force): checked before any run."""
    from reports.report_files import foreign, refusal

    left = foreign(out)
    if left and not force:
        raise TraceError(refusal(left))


def _write_junit(path: Path, runs: list[CaseResult], cases: list[LoadedScenario]) -> None:
    from runner.ci.junit import write_junit
    from runner.cli.outcomes import junit_case

    write_junit(path, [junit_case(r, loaded) for r, loaded in zip(runs, cases, strict=True)])
