"""`scenario run`: run every case of every file, print verdict tables and a summary."""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.markup import escape

from backends.errors import BackendError, BackendNotInstalled, EngineFailure
from backends.registry import DEFAULT_BACKEND
from runner.cli import options
from runner.cli.progress import BatchProgress, wanted
from runner.errors import OutputError, ScenarioError, ScenarioValidationError, TraceError, UsageError
from runner.exec.cases import Case, CaseResult
from runner.language.load import BASE_CASE, LoadedScenario, load_files, parse_overrides
from runner.trace.output import OUTPUT_ERRNOS

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID

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
    run.add_argument("--rerun", action="store_true",
                     help="also write each trace as a Rerun recording, <trace>.rrd (the `viewers` extra)")  # fmt: skip
    options.add_overrides(run)
    out = run.add_mutually_exclusive_group()
    out.add_argument("--quiet", "-q", action="store_true", help="print only failures and the summary")
    out.add_argument("--json", action="store_true", help="print the results as JSON")
    run.add_argument(
        "--junit", type=Path, metavar="FILE", help="also write a JUnit XML report (one testcase per case) to FILE"
    )
    run.add_argument("--force", action="store_true",
                     help="also overwrite files under the traces' names that scenario did not write")  # fmt: skip
    run.add_argument(
        "--isolate",
        action="store_true",
        help="run each case in a process of its own (every case runs in a child process anyway: a crash is "
        "exit 3 with its signal, and the trace up to that point is kept)",
    )
    run.add_argument(
        "--timeout",
        type=float,
        default=None,
        metavar="S",
        help="stop a run after S seconds of wall time (default: the scenario's world.budget, else 3600)",
    )
    run.add_argument(
        "--record-every", type=int, default=1, metavar="K",
        help="record every K-th step in the trace, and the last (default 1; assertions still check every step)",
    )  # fmt: skip
    run.add_argument(
        "--trace-process", action="store_true", help="format and write traces in a second process (uses a free core)"
    )
    add_arguments(run)


def _result_json(res: CaseResult, loaded: LoadedScenario) -> dict[str, Any]:
    r = res.result
    base: dict[str, Any] = {"scenario": loaded.model.scenario, "variant": loaded.variant, "backend": res.case.backend}
    if r is None:
        exit = res.exit
        return {**base, "status": res.status, "exit_code": int(exit.code), "message": exit.headline,
                "trace": res.trace, "verdicts": [], "events": []}  # fmt: skip
    return {
        **base,
        "status": r.status,
        "exit_code": int(res.exit.code),
        "end_time": r.end_time,
        "steps": r.steps,
        "trace": r.trace,
        "failure": r.failure,
        "failure_detail": r.extra or None,
        "engine_messages": r.engine_messages,
        "verdicts": [v.as_dict() for v in r.verdicts],
        "events": [{"time": t, "name": n, "source": s} for t, n, s in r.events],
    }


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    cases: list[LoadedScenario] = []
    results: list[CaseResult] = []
    try:
        code = _execute(args, out, err, cases, results)
    except (ScenarioError, BackendError, TraceError) as exc:
        if args.junit:
            _write_junit(args, cases, results, exc)
        raise
    if args.junit:
        _write_junit(args, cases, results, None)
    return code


def _write_junit(
    args: argparse.Namespace, cases: list[LoadedScenario], results: list[CaseResult], exc: Exception | None
) -> None:
    """The report of what ran; what stopped the command before it ran (bad input, a missing engine) is an
    error case."""
    from runner.ci.junit import from_error, write_junit
    from runner.cli.outcomes import junit_case

    junit = [junit_case(r, c) for r, c in zip(results, cases, strict=False)]
    if isinstance(exc, ScenarioValidationError):
        by_file: dict[str, list[str]] = {}
        for issue in exc.issues:
            by_file.setdefault(issue.file, []).append(str(issue))
        junit += [from_error(f, b, "\n".join(lines)) for f, lines in by_file.items() for b in _backend_names(args)]
    elif exc is not None:
        kind = "engine-failure" if isinstance(exc, (BackendNotInstalled, EngineFailure)) else "bad-input"
        where = args.files[0] if args.files else "scenario"
        junit += [from_error(where, b, str(exc), kind) for b in _backend_names(args)]
    write_junit(args.junit, junit)


def _backend_names(args: argparse.Namespace) -> list[str]:
    """The backends as the command line named them (`-b a,b` or `-b a -b b`), for a JUnit error case per
    backend before the names were checked."""
    names = [n.strip() for text in (args.backend or [args.backend_default]) for n in text.split(",")]
    return list(dict.fromkeys(n for n in names if n)) or [args.backend_default]


def _check(args: argparse.Namespace) -> None:
    if args.record_every < 1:
        raise UsageError(
            f"Invalid `--record-every`. Expected a positive number of steps. Received: {args.record_every}"
        )
    if args.timeout is not None and not (args.timeout > 0 and math.isfinite(args.timeout)):
        raise UsageError(f"Invalid `--timeout`. Expected a positive number of seconds. Received: {args.timeout}")
    if args.rerun and args.no_trace:
        raise UsageError("`--rerun` converts the traces; it does not combine with `--no-trace`")
    if args.rerun and importlib.util.find_spec("rerun") is None:
        raise ScenarioError("--rerun: rerun-sdk is not installed (pip install '.[viewers]')")
    if args.isolate and args.executor != "local":
        raise UsageError("`--isolate` runs each case in a local process of its own; it does not combine with Ray")


def _execute(
    args: argparse.Namespace, out: Console, err: Console, cases: list[LoadedScenario], results: list[CaseResult]
) -> int:
    """Every case on each backend asked for, one backend after the other; ``cases`` receives the case of
    each run, in run order, and ``results`` its result. The most severe exit code wins."""
    from runner.cli.outcomes import print_summary
    from runner.exec.executors import check_outputs, make_executor, status_code

    backends = options.backend_names(args)  # unknown: bad input (exit 2); missing: exit 3; before anything runs
    overrides = parse_overrides(args.set)
    _check(args)
    loaded = load_files(options.scenario_files(args.files), args.variant, args.all_variants, overrides)
    work = [(case, backend) for backend in backends for case in loaded]
    cases.extend(case for case, _ in work)
    out_dir: Path | None = None if args.no_trace else args.out
    if out_dir is not None:
        for backend in backends:
            _refuse_duplicates(out_dir, loaded, backend)
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            message = f"cannot use {out_dir} as the trace folder: {exc.strerror or exc}"
            if exc.errno in OUTPUT_ERRNOS:  # read-only, not permitted, full: exit 74
                raise OutputError(message) from None
            raise ScenarioError(message) from None
    jobs = [_case(args, c, b, overrides, out_dir) for c, b in work]
    check_outputs(jobs, args.force)  # files the tool did not write: refused before anything runs
    executor = make_executor(args.executor, args.jobs, args.ray_address, isolate=args.isolate, force=args.force)
    shown = _Shown(args, out, err, cases, results)
    watched = wanted(err, args.quiet, args.json)
    try:
        if watched and len(jobs) > 1:  # a batch: cases done, running, failed, ETA
            with BatchProgress(err, len(jobs), then=shown.add) as bar:
                executor.run(jobs, bar.result, None, bar.start)
        elif watched:  # one case: its steps
            with _progress(err) as progress:
                executor.run(jobs, shown.add, _advance(progress, cases))
        else:
            executor.run(jobs, shown.add, None)
    finally:
        executor.close()
    if args.json:
        body = {"results": [_result_json(r, c) for r, c in zip(results, cases, strict=True)]}
        out.print_json(json.dumps(body, allow_nan=False, default=str))
    else:
        print_summary(out, results, [(c.model.scenario, c.variant) for c in cases])
    code: int = status_code(results)
    if out_dir is not None and any(r.trace is not None for r in results):
        from runner.cli.layouts import leave_layout

        code = leave_layout(err, [out_dir], cases, code)  # the 3D scene, asserted quantities, events, log
    if args.rerun:
        from runner.cli.commands.export import export_rrds, rrd_path

        traces = [Path(r.trace) for r in results if r.trace is not None and Path(r.trace).exists()]
        export_rrds([(t, rrd_path(t)) for t in traces], err)
    return code


def _case(args: argparse.Namespace, loaded: LoadedScenario, backend: str, overrides: tuple[tuple[str, Any], ...],
          out_dir: Path | None) -> Case:  # fmt: skip
    from runner.exec.executors import estimate_cost
    from runner.sim.budget import DEFAULT_BUDGET
    from runner.sim.run import trace_path

    budget = args.timeout if args.timeout is not None else (loaded.model.world.budget or DEFAULT_BUDGET)
    return Case(
        str(loaded.path), None if loaded.variant == BASE_CASE else loaded.variant, backend, overrides,
        None if out_dir is None else str(out_dir), cost=estimate_cost(loaded), record_every=args.record_every,
        trace_process=args.trace_process, budget=budget, sha256=loaded.sha256,
        trace=None if out_dir is None else str(trace_path(out_dir, loaded, backend)),
        scenario=loaded.model.scenario, loaded=loaded,
    )  # fmt: skip


class _Shown:
    """Prints each case as its result arrives, in case order (a parallel run prints what a serial one does)."""

    def __init__(self, args: argparse.Namespace, out: Console, err: Console, cases: list[LoadedScenario],
                 results: list[CaseResult]) -> None:  # fmt: skip
        self.args, self.out, self.err, self.cases, self.results = args, out, err, cases, results
        self.waiting: dict[int, CaseResult] = {}

    def add(self, index: int, res: CaseResult) -> None:
        from runner.cli.outcomes import print_problem, print_result

        self.waiting[index] = res
        while len(self.results) in self.waiting:
            res = self.waiting.pop(len(self.results))
            self.results.append(res)
            if res.result is not None:
                if res.output.strip():
                    self.err.print(escape(res.output.rstrip()), highlight=False)  # what the engine printed
                if not self.args.json:
                    print_result(self.out, res.result, self.args.quiet)
            else:
                print_problem(self.err, res)


def _progress(err: Console) -> Progress:
    # imported here: a run that shows no bar (--quiet, --json, no terminal) does not import it
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    return Progress(TextColumn("{task.description}", markup=False), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
                    TimeRemainingColumn(), console=err, transient=True, auto_refresh=False)  # fmt: skip


def _advance(progress: Progress, cases: list[LoadedScenario]) -> Any:
    tasks: dict[int, TaskID] = {}

    def advance(index: int, k: int, n: int) -> None:
        if index not in tasks:
            for done in tasks.values():
                progress.remove_task(done)
            tasks.clear()
            tasks[index] = progress.add_task(f"{cases[index].model.scenario} · {cases[index].variant}", total=n)
        progress.update(tasks[index], completed=k, total=n)
        progress.refresh()

    return advance


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

