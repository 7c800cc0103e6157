"""`scenario sweep`: run the cross product of parameter values x variants x backends, and tabulate it.

Metrics (``--metric EXPR``) are evaluated on the last recorded state of each case's trace, once the cases
(run by runner.exec.executors) are done (runner.cli.sweep_metrics); the tables and the plot are
runner.cli.sweep_table's.

Writes into ``--out``: ``sweep.csv`` and ``sweep.json`` (one row per case: parameter values, variant,
backend, status, every assertion's verdict, every ``--metric`` evaluated on the final recorded state),
``sweep.svg`` when a parameter is numeric (each metric, or the share of assertions passed, against the
first numeric parameter), and the traces under ``traces/<case>/``. Nothing in the tables depends on
wall time or on the executor: the same sweep gives the same files locally and on Ray.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import json
import math
import re
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape

from backends.registry import DEFAULT_BACKEND
from runner.cli import options
from runner.cli.sweep_metrics import check_metrics, final_values
from runner.cli.sweep_table import build_table, plot, print_table, to_csv
from runner.errors import UsageError

NAME = "sweep"
HELP = "run a scenario over a grid of parameter values (x variants x backends) and tabulate the results"
DEFAULT_OUT = Path("traces/sweep")


def configure(p: argparse.ArgumentParser) -> None:
    from runner.exec.executors import add_arguments

    p.add_argument("file", type=Path, metavar="FILE")
    p.add_argument("--param", action="append", default=[], required=True, metavar="NAME=v1,v2,...",
                   help="a declared parameter's name (or a --set path) and its values; repeat for a grid")  # fmt: skip
    options.add_backend(p, DEFAULT_BACKEND)
    options.add_variant_choice(p)
    p.add_argument("--metric", action="append", default=[], metavar="EXPR",
                   help="an expression evaluated at each run's end, e.g. 'max(crate.pos.z)' (repeatable)")  # fmt: skip
    options.add_overrides(p)
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output folder (default {DEFAULT_OUT})")
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="stop a run after S seconds of wall time (default: the scenario's world.budget, else 3600)")
    p.add_argument("--force", action="store_true",
                   help="also overwrite files under the traces' names that scenario did not write")  # fmt: skip
    p.add_argument("--batch", action="store_true",
                   help="run each backend's cases as the worlds of one batched engine where it can (docs/batch.md); "
                        "elsewhere they run separately and the reason is printed")  # fmt: skip
    p.add_argument("--traces", action="store_true",
                   help="with --batch: also write each case's trace (always written without --batch, and with "
                        "--metric, which reads them)")  # fmt: skip
    out = p.add_mutually_exclusive_group()
    out.add_argument("--quiet", "-q", action="store_true", help="print only the summary")
    out.add_argument("--json", action="store_true", help="print the table as JSON")
    add_arguments(p)


def split_values(text: str) -> list[str]:
    """``1,2,[0, 0, 1]`` -> ['1', '2', '[0, 0, 1]']: commas inside brackets or braces do not split."""
    parts, depth, current = [], 0, ""
    for ch in text:
        depth += (ch in "[{") - (ch in "]}")
        if ch == "," and depth == 0:
            parts.append(current.strip())
            current = ""
        else:
            current += ch
    parts.append(current.strip())
    if any(not v for v in parts):
        raise UsageError(f"Invalid `--param` values `{text}`. Expected a comma-separated list of values.")
    return parts


def parse_params(items: list[str], declared: set[str]) -> list[tuple[str, list[Any]]]:
    """``--param`` items -> [(--set path, values)]; the name of a parameter the file declares means params.NAME;
    another name without a dot (not a top-level key either) is an error naming the closest declared parameter."""
    import difflib

    from runner.language.load import parse_overrides
    from runner.language.model import Scenario

    top = {f.alias or n for n, f in Scenario.model_fields.items()}
    grid: list[tuple[str, list[Any]]] = []
    for item in items:
        name, sep, values = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise UsageError(f"Invalid `--param {item}`. Expected NAME=v1,v2,...")
        if "." not in name and name not in declared and name not in top:
            close = difflib.get_close_matches(name, sorted(declared), n=1, cutoff=0.6)
            hint = f"did you mean `{close[0]}`?" if close else f"declared: {', '.join(sorted(declared)) or 'none'}"
            raise UsageError(f"`--param {item}`: unknown parameter `{name}`; {hint}")
        if name in declared:
            name = f"params.{name}"
        if name in (g[0] for g in grid):
            raise UsageError(f"`--param {name}` is given twice")
        grid.append((name, [v for _, v in parse_overrides([f"{name}={v}" for v in split_values(values)])]))
    return grid


def _probe(file: Path, fixed: tuple[tuple[str, Any], ...], grid: list[tuple[str, list[Any]]]) -> None:
    """Each --param path set to its first value: a path the file does not declare is refused naming `--param`."""
    from runner.errors import Issue, ScenarioValidationError
    from runner.language.load import load_scenario

    try:
        load_scenario(file, None, fixed + tuple((name, values[0]) for name, values in grid))
    except ScenarioValidationError as exc:
        names = {f"--set {name}" for name, _ in grid}
        raise ScenarioValidationError([
            Issue(i.file, i.line, i.column, "--param" + i.path.removeprefix("--set"), i.message) if i.path in names
            else i for i in exc.issues
        ]) from None  # fmt: skip


def _slug(values: dict[str, Any]) -> str:
    text = "_".join(f"{k.removeprefix('params.')}={v}" for k, v in values.items())
    return re.sub(r"[^A-Za-z0-9_.=-]+", "-", text)[:80]


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.cli.outcomes import print_problem
    from runner.cli.progress import BatchProgress, wanted
    from runner.exec.executors import (
        Case,
        CaseResult,
        Executor,
        check_outputs,
        estimate_cost,
        make_executor,
        status_code,
    )
    from runner.language.load import load_all, load_scenario, parse_overrides
    from runner.sim.budget import DEFAULT_BUDGET
    from runner.sim.run import trace_path

    if args.batch and args.executor != "local":
        raise UsageError("`--batch` runs its batches on this machine; it cannot be combined with `--executor ray`")
    if args.timeout is not None and not (args.timeout > 0 and math.isfinite(args.timeout)):
        raise UsageError(f"Invalid `--timeout`. Expected a positive number of seconds. Received: {args.timeout}")
    fixed = parse_overrides(args.set)
    base = load_scenario(args.file, None, fixed)
    grid = parse_params(args.param, set(base.model.params))
    _probe(args.file, fixed, grid)
    backends = options.backend_names(args)
    check_metrics(args.metric, base.model)
    names = [n for n, _ in grid]
    combos = [dict(zip(names, values, strict=True)) for values in itertools.product(*(v for _, v in grid))]
    cases: list[Case] = []
    labels: list[dict[str, Any]] = []
    loads: list[Any] = []
    traced = not args.batch or args.traces or bool(args.metric)  # a batched sweep writes traces on request
    for k, combo in enumerate(combos):
        overrides = fixed + tuple(combo.items())
        for loaded in load_all(args.file, args.variant, args.all_variants, overrides):  # bad values: exit 2 here
            variant = None if loaded.variant == "base" else loaded.variant
            for b in backends:
                folder = args.out / "traces" / f"{len(cases):03d}_{_slug(combo)}"
                budget = args.timeout if args.timeout is not None else (loaded.model.world.budget or DEFAULT_BUDGET)
                cases.append(Case(str(args.file), variant, b, overrides, str(folder) if traced else None,
                                  cost=estimate_cost(loaded), budget=budget, sha256=loaded.sha256,
                                  trace=str(trace_path(folder, loaded, b)) if traced else None,
                                  scenario=loaded.model.scenario, loaded=loaded))  # fmt: skip
                labels.append({"combo": k, "params": combo, "variant": loaded.variant, "backend": b})
                loads.append(loaded)
    check_outputs(cases, args.force)
    executor: Executor = make_executor(args.executor, args.jobs, args.ray_address, force=args.force)
    if args.batch:
        executor = batched(executor, args, err)
    bar = BatchProgress(err, len(cases)) if wanted(err, args.quiet, args.json) else None

    def done(i: int, r: CaseResult) -> None:
        if bar is not None:
            bar.result(i, r)
        if r.result is None:
            print_problem(err, r)

    try:
        with bar if bar is not None else contextlib.nullcontext():
            results = executor.run(cases, done, None if bar is None else bar.steps, None if bar is None else bar.start)
    finally:
        executor.close()
    metrics = [
        final_values(loaded, Path(r.result.trace), args.metric, label["backend"])
        if args.metric and r.result and r.result.trace
        else {}
        for loaded, r, label in zip(loads, results, labels, strict=True)
    ]
    table = build_table(args.file, grid, labels, results, metrics, args.metric)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "sweep.json").write_text(json.dumps(table, indent=2, allow_nan=False) + "\n")
    (args.out / "sweep.csv").write_text(to_csv(table))
    svg = plot(table)
    if svg:
        (args.out / "sweep.svg").write_text(svg)
    if args.json:
        out.print_json(json.dumps(table, allow_nan=False))
    else:
        print_table(out, table, args.out, bool(svg), args.quiet)
    return status_code(results)  # the most severe case: bad input or a missing engine in some case is exit 2/3


def batched(separate: Any, args: argparse.Namespace, err: Console) -> Any:
    """The executor of ``--batch``: each backend's (and variant's) cases as one batch, else ``separate``
    (runner.exec.batched); a fallback prints its reason."""
    from runner.exec.batched import BatchedExecutor

    def fallback(which: str, reason: str) -> None:
        err.print(f"--batch: {escape(reason)}; {escape(which)} run separately")

    return BatchedExecutor(separate, args.jobs, force=args.force, on_fallback=fallback)
