"""`scenario run`: run every case of every file, print verdict tables and a summary."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeRemainingColumn

from backends.errors import BackendError, BackendNotInstalled, EngineFailure
from backends.registry import DEFAULT_BACKEND
from runner.cli import options
from runner.cli.render import verdict_table
from runner.errors import ExitCode, ScenarioError, ScenarioValidationError, UsageError
from runner.language.load import LoadedScenario, load_files, parse_overrides
from runner.sim.run import run_loaded
from runner.sim.session import RunResult

NAME = "run"
HELP = "run scenarios and print verdicts"
DEFAULT_OUT = Path("traces")


def configure(run: argparse.ArgumentParser) -> None:
    from runner.exec.executors import add_arguments

    options.add_scenario_files(run)
    options.add_backend(run, DEFAULT_BACKEND)
    options.add_variant_choice(run)
    run.add_argument("--out", type=Path, default=DEFAULT_OUT, help="folder for the traces (default: traces/)")
    run.add_argument("--no-trace", action="store_true", help="do not write traces")
    options.add_overrides(run)
    out = run.add_mutually_exclusive_group()
    out.add_argument("--quiet", "-q", action="store_true", help="print only failures and the summary")
    out.add_argument("--json", action="store_true", help="print the results as JSON")
    run.add_argument(
        "--junit", type=Path, metavar="FILE", help="also write a JUnit XML report (one testcase per case) to FILE"
    )
    run.add_argument("--force", action="store_true", help="overwrite traces that already exist")
    run.add_argument(
        "--isolate",
        action="store_true",
        help="run the engine in a child process: a crash (even a "
        "segfault) is reported as exit 3 with its signal, and the trace up to that point is kept",
    )
    run.add_argument(
        "--timeout",
        type=float,
        default=None,
        metavar="S",
        help="with --isolate: stop a run after S seconds of wall time",
    )
    run.add_argument(
        "--record-every", type=int, default=1, metavar="K",
        help="record every K-th step in the trace, and the last (default 1; assertions still check every step)",
    )  # fmt: skip
    run.add_argument(
        "--trace-process", action="store_true", help="format and write traces in a second process (uses a free core)"
    )
    add_arguments(run)


def _result_json(r: RunResult) -> dict[str, Any]:
    return {
        "scenario": r.scenario,
        "variant": r.variant,
        "backend": r.backend,
        "status": r.status,
        "end_time": r.end_time,
        "steps": r.steps,
        "trace": r.trace,
        "failure": r.failure,
        "failure_detail": r.extra or None,
        "verdicts": [v.as_dict() for v in r.verdicts],
        "events": [{"time": t, "name": n, "source": s} for t, n, s in r.events],
    }


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    """Every case on each backend asked for, one backend after the other; the worst exit code wins."""
    results: list[RunResult] = []
    cases: list[LoadedScenario] = []
    backends = options.backend_names(args)
    crashed: list[str] = []
    code: int = ExitCode.OK
    try:
        for i, backend in enumerate(backends):
            args.backend = backend
            code = _execute(args, out, err, cases, results, crashed, final=i == len(backends) - 1)
    except (ScenarioError, BackendError) as exc:
        if args.junit:
            _write_junit(args, cases, results, exc)
        raise
    if args.junit:
        _write_junit(args, cases, results, None)
    return code


def _write_junit(
    args: argparse.Namespace, cases: list[LoadedScenario], results: list[RunResult], exc: Exception | None
) -> None:
    """The report of what ran; what stopped the command (bad input, a missing engine) is an error case."""
    from runner.ci.junit import from_error, from_result, write_junit

    junit = [from_result(r, _case_of(r, cases)) for r in results]
    if isinstance(exc, ScenarioValidationError):
        by_file: dict[str, list[str]] = {}
        for issue in exc.issues:
            by_file.setdefault(issue.file, []).append(str(issue))
        junit += [from_error(f, args.backend, "\n".join(lines)) for f, lines in by_file.items()]
    elif exc is not None:
        kind = "engine-failure" if isinstance(exc, (BackendNotInstalled, EngineFailure)) else "bad-input"
        case = cases[len(results) % len(cases)] if cases else None
        where = case.path if case is not None else (args.files[0] if args.files else "scenario")
        junit.append(from_error(where, args.backend, str(exc), kind, case.variant if case is not None else "load"))
    write_junit(args.junit, junit)


def _case_of(result: RunResult, cases: list[LoadedScenario]) -> LoadedScenario | None:
    return next((c for c in cases if c.model.scenario == result.scenario and c.variant == result.variant), None)


def _execute(
    args: argparse.Namespace,
    out: Console,
    err: Console,
    loaded: list[LoadedScenario],
    results: list[RunResult],
    crashed: list[str],
    final: bool = True,
) -> int:
    """The cases on ``args.backend`` (loaded once, by the first backend's call, into ``loaded``); results and
    crashes accumulate over the backends; the last backend's call prints the summary and gives the exit code."""
    overrides = parse_overrides(args.set)
    if args.record_every < 1:
        raise UsageError(
            f"Invalid `--record-every`. Expected a positive number of steps. Received: {args.record_every}"
        )
    if not loaded:
        loaded.extend(load_files(options.scenario_files(args.files), args.variant, args.all_variants, overrides))
    cases = loaded
    out_dir: Path | None = None if args.no_trace else args.out
    if out_dir is not None:
        _refuse_duplicates(out_dir, cases, args.backend)
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ScenarioError(f"cannot use {out_dir} as the trace folder: {exc.strerror or exc}") from None
    if out_dir is not None and not args.force:
        _refuse_overwrite(out_dir, cases, args.backend)
    show_progress = err.is_terminal and not (args.quiet or args.json) and not args.isolate
    parallel = args.jobs > 1 or args.executor != "local"
    ready, error = _run_parallel(args, err, cases, out_dir, overrides, crashed) if parallel else (None, None)
    run_options = {"record_every": args.record_every, "trace_process": args.trace_process}
    for i, case in enumerate(cases if ready is None else cases[: len(ready)]):
        if ready is not None:
            result = ready[i]
            if result is None:  # crashed: listed in `crashed`
                continue
        elif args.isolate:
            result = _run_isolated(case, args, out_dir, err, crashed)
            if result is None:
                continue
        elif show_progress:
            with Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                TextColumn("{task.percentage:>3.0f}%"),
                TimeRemainingColumn(),
                console=err,
                transient=True,
            ) as progress:
                task = progress.add_task(f"{case.model.scenario} · {case.variant}", total=None)

                def advance(k: int, n: int, task: TaskID = task) -> None:
                    progress.update(task, completed=k, total=n)

                result = run_loaded(case, args.backend, out_dir, advance, **run_options)
        else:
            result = run_loaded(case, args.backend, out_dir, **run_options)
        results.append(result)
        if not args.json:
            _print_result(out, result, args.quiet)
    if error is not None:
        error.raise_error()  # bad input or a missing engine, as a serial run would stop on it
    if not final:
        return ExitCode.OK
    if args.json:
        out.print_json(json.dumps({"results": [_result_json(r) for r in results]}, allow_nan=False, default=str))
    else:
        _print_summary(out, results, len(crashed))
    for line in crashed:
        out.print(f"[bold red]{escape(line)}[/]")
    if crashed or any(r.status == "engine-failure" for r in results):
        return ExitCode.ENGINE_FAILURE
    return ExitCode.OK if all(r.passed for r in results) else ExitCode.ASSERTION_FAILED


def _print_result(out: Console, result: RunResult, quiet: bool) -> None:
    if result.failure:
        out.print(
            f"[bold red]engine failure[/] in {result.scenario} · {result.variant} · {result.backend}: "
            f"{escape(result.failure)}"
        )
        detail = result.extra.get("last_good")
        if detail:
            out.print(f"  last good state of `{result.extra.get('body')}`: {escape(json.dumps(detail))}")
    if result.verdicts and (not quiet or not result.passed):
        out.print(verdict_table(result, failures_only=quiet))
    if result.trace and not quiet:
        out.print(f"  trace: {escape(result.trace)}")


def _print_summary(out: Console, results: list[RunResult], crashed: int = 0) -> None:
    passed = sum(r.passed for r in results)
    total = len(results) + crashed
    checks = sum(len(r.verdicts) for r in results)
    failed_checks = sum(not v.passed for r in results for v in r.verdicts)
    colour = "green" if passed == total else "red"
    out.print(f"[bold {colour}]{passed}/{total} runs passed[/] ({checks - failed_checks}/{checks} assertions)")
    for r in results:
        if not r.passed:
            out.print(f"  [red]{r.status}[/]: {r.scenario} · {r.variant} · {r.backend}")


def _refuse_duplicates(out_dir: Path, cases: list[LoadedScenario], backend: str) -> None:
    """Two cases of one command must not write the same trace (same scenario name and variant)."""
    from runner.sim.run import trace_path

    first: dict[Path, LoadedScenario] = {}
    for case in cases:
        path = trace_path(out_dir, case, backend)
        if path in first:
            raise ScenarioError(
                f"{first[path].path} and {case.path} would both write {path} (scenario `{case.model.scenario}`, "
                f"variant `{case.variant}`); give them different scenario names or run them separately"
            )
        first[path] = case


def _refuse_overwrite(out_dir: Path, cases: list[LoadedScenario], backend: str) -> None:
    """Refuse before anything runs if a trace of these cases is already there (unless --force)."""
    from runner.sim.run import trace_path

    paths = [trace_path(out_dir, c, backend) for c in cases]
    existing = [q for p in paths for q in (p, p.with_name(p.name + ".partial")) if q.exists()]
    if existing:
        names = ", ".join(str(p) for p in existing[:3]) + (
            f" and {len(existing) - 3} more" if len(existing) > 3 else ""
        )
        raise ScenarioError(
            f"{names} already exist{'s' if len(existing) == 1 else ''}; pass --force to overwrite, "
            "or choose another --out folder"
        )


def _run_isolated(
    case: LoadedScenario, args: argparse.Namespace, out_dir: Path | None, err: Console, crashed: list[str]
) -> RunResult | None:
    """One case in a child process; a crash or time-out is recorded in ``crashed`` and gives no result."""
    from runner.exec.isolation import run_isolated

    run = run_isolated(case, args.backend, out_dir, timeout=args.timeout)
    if run.result is not None:
        return run.result
    where = f" (trace kept: {run.trace})" if run.trace is not None else ""
    crashed.append(f"{run.label}: {case.model.scenario} · {case.variant} · {args.backend}{where}")
    if run.message:
        err.print(escape(run.message))
    return None


def _run_parallel(
    args: argparse.Namespace,
    err: Console,
    cases: list[LoadedScenario],
    out_dir: Path | None,
    overrides: tuple[tuple[str, Any], ...],
    crashed: list[str],
) -> tuple[list[RunResult | None], Any]:
    """Every case at once, ``-j`` at a time (runner.exec.executors; with --isolate, runner.exec.isolation). Returns
    the results in case order up to the first case that could not run (bad input, a missing engine),
    with that case, whose error the caller raises; None for a crash (a line in ``crashed``)."""
    from runner.exec.executors import Case, estimate_cost, make_executor

    label = f"{args.backend}"
    count = [0]

    def tick(*_: Any) -> None:
        count[0] += 1
        if err.is_terminal and not (args.quiet or args.json):
            err.print(f"  {count[0]}/{len(cases)} cases done", end="\r")

    if args.isolate:
        if args.executor != "local":
            raise UsageError("`--isolate` runs each case in a local child process; it does not combine with Ray")
        from runner.exec.isolation import run_many

        isolated = run_many([(c, args.backend) for c in cases], out_dir, jobs=args.jobs, timeout=args.timeout,
                            on_done=tick)  # fmt: skip
        ready: list[RunResult | None] = []
        for case, run in zip(cases, isolated, strict=True):
            if run.result is None:
                where = f" (trace kept: {run.trace})" if run.trace is not None else ""
                crashed.append(f"{run.label}: {case.model.scenario} · {case.variant} · {label}{where}")
            ready.append(run.result)
        return ready, None
    jobs = [
        Case(str(c.path), None if c.variant == "base" else c.variant, args.backend, overrides,
             None if out_dir is None else str(out_dir), cost=estimate_cost(c), record_every=args.record_every)
        for c in cases
    ]  # fmt: skip
    executor = make_executor(args.executor, args.jobs, args.ray_address)
    try:
        done = executor.run(jobs, tick)
    finally:
        executor.close()
    ready = []
    for case, r in zip(cases, done, strict=True):
        if r.status == "error":
            return ready, r
        if r.result is None:
            crashed.append(f"{r.status}: {case.model.scenario} · {case.variant} · {label} ({r.failure})")
        ready.append(r.result)
    return ready, None
