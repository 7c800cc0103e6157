"""`scenario sweep`: run the cross product of parameter values x variants x backends, and tabulate it.

Metrics (``--metric EXPR``) are evaluated here, on the last recorded state of each case's trace, once the
cases (run by runner.exec.executors) are done.

Writes into ``--out``: ``sweep.csv`` and ``sweep.json`` (one row per case: parameter values, variant,
backend, status, every assertion's verdict, every ``--metric`` evaluated on the final recorded state),
``sweep.svg`` when a parameter is numeric (each metric, or the share of assertions passed, against the
first numeric parameter), and the traces under ``traces/<case>/``. Nothing in the tables depends on
wall time or on the executor: the same sweep gives the same files locally and on Ray.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import itertools
import json
import math
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from backends.registry import DEFAULT_BACKEND
from runner.cli import options
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
        _print(out, table, args.out, bool(svg), args.quiet)
    return status_code(results)  # the most severe case: bad input or a missing engine in some case is exit 2/3


def batched(separate: Any, args: argparse.Namespace, err: Console) -> Any:
    """The executor of ``--batch``: each backend's (and variant's) cases as one batch, else ``separate``
    (runner.exec.batched); a fallback prints its reason."""
    from runner.exec.batched import BatchedExecutor

    def fallback(which: str, reason: str) -> None:
        err.print(f"--batch: {escape(reason)}; {escape(which)} run separately")

    return BatchedExecutor(separate, args.jobs, force=args.force, on_fallback=fallback)


def final_values(loaded: Any, trace_path: Path, expressions: Sequence[str], backend: str) -> dict[str, Any]:
    """Each expression evaluated on the last recorded state of a trace that ``backend`` wrote (bodies, joints,
    state variables, contacts and event counts, ``eps`` its precision's; ``playing()`` has no recorded state
    and is refused)."""
    import numpy as np

    from backends.registry import entry
    from backends.types import BodyStates, JointStates
    from reports.trace_reader import TraceReadError, read_trace
    from runner.compile.program import build_program
    from runner.errors import TraceError
    from runner.language.expressions import compile_expression
    from runner.sim.resolver import Snapshot, StateResolver

    program = build_program(loaded)
    world = program.world
    try:
        trace = read_trace(trace_path)
    except TraceReadError as exc:
        raise TraceError(f"metrics: {exc}") from exc
    snap = Snapshot()
    if not trace.times.size:
        raise UsageError(f"metrics: the trace {trace_path.name} recorded no step")
    snap.time = float(trace.times[-1])
    rows = np.array([np.concatenate([s.pos[-1], s.quat[-1], s.vel[-1], s.angvel[-1]])
                     for s in (trace.bodies[b.name] for b in world.bodies)]).reshape(len(world.bodies), 13)  # fmt: skip
    snap.bodies = BodyStates.from_rows(rows)
    j = [trace.joints[x.name] for x in world.joints]
    snap.joints = JointStates(*(np.array([getattr(s, f)[-1] for s in j], dtype=float) for f in
                                ("position", "velocity", "motor_force")))  # fmt: skip
    state = {k: v[-1] for k, v in trace.state.items()}
    last = trace.contacts[-1] if trace.contacts and math.isclose(trace.contacts[-1][0], snap.time) else (0.0, [])
    touching = {frozenset((p["a"], p["b"])) for p in last[1]}

    def refuse(args: Sequence[Any]) -> Any:
        raise UsageError("metrics: playing() has no recorded state; use a state variable instead")

    functions: dict[str, Callable[[Sequence[Any]], Any]] = {
        "contact": lambda a: frozenset((str(a[0]), str(a[1]))) in touching,
        "count": lambda a: sum(e.name == str(a[0]) for e in trace.events),
        "playing": refuse,
    }
    eps = entry(backend).precision.eps
    resolver = StateResolver(world, program.groups, state, dict(loaded.model.params), snap, functions, eps=eps)
    out: dict[str, Any] = {}
    for text in expressions:
        try:
            out[text] = compile_expression(text).evaluate(resolver)
        except (KeyError, ValueError, TypeError, ZeroDivisionError) as exc:
            raise UsageError(f"metric `{text}` cannot be evaluated: {exc}") from exc
    return out


def check_metrics(texts: list[str], model: Any) -> None:
    """Refuse, before anything runs, a metric that does not parse or reads what a trace does not hold."""
    from runner.language.expressions import compile_expression
    from runner.language.names import readable_names

    valid = set(readable_names(model))
    for text in texts:
        try:
            expr = compile_expression(text)
        except ValueError as exc:
            raise UsageError(f"Invalid `--metric {text}`: {exc}") from exc
        unknown = sorted(n for n in expr.names if n not in valid) + sorted(expr.calls - {"contact", "count"})
        if unknown:
            raise UsageError(f"Invalid `--metric {text}`: it reads {', '.join(unknown)}, which no trace holds "
                             f"(names: bodies, joints, state., param., time; functions: contact, count)")  # fmt: skip


def _json_value(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, list):
        return [_json_value(x) for x in v]
    return v


def build_table(file: Path, grid: list[tuple[str, list[Any]]], labels: list[dict[str, Any]], results: list[Any],
                values: list[dict[str, Any]], metrics: list[str]) -> dict[str, Any]:  # fmt: skip
    assertions: list[str] = []
    rows = []
    for i, (label, r, found) in enumerate(zip(labels, results, values, strict=True)):
        verdicts = {v.name: v for v in (r.result.verdicts if r.result is not None else [])}
        assertions += [n for n in verdicts if n not in assertions]
        trace = r.result.trace if r.result is not None else None
        rows.append({
            "case": i,
            "params": {k: _json_value(v) for k, v in label["params"].items()},
            "variant": label["variant"],
            "backend": label["backend"],
            "status": r.status,
            "passed": sum(v.passed for v in verdicts.values()),
            "failed": sum(not v.passed for v in verdicts.values()),
            "verdicts": {n: {"passed": v.passed, "status": v.status, "measured": v.measured}
                         for n, v in verdicts.items()},
            "metrics": {m: _json_value(found.get(m)) for m in metrics},
            "failure": r.failure,
            "trace": str(Path(trace).relative_to(Path(r.case.out_dir).parent.parent)) if trace else None,
        })  # fmt: skip
    return {"file": file.name, "parameters": [n for n, _ in grid], "metrics": list(metrics),
            "assertions": assertions, "rows": rows}  # fmt: skip


def _mark(verdict: dict[str, Any]) -> str:
    """pass, FAIL, or known limit (an expected failure, which does not fail the case)."""
    return "known limit" if verdict.get("status") == "known limit" else "pass" if verdict["passed"] else "FAIL"


def to_csv(table: dict[str, Any]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    names, assertions, metrics = table["parameters"], table["assertions"], table["metrics"]
    w.writerow(["case", *names, "variant", "backend", "status", "passed", "failed", *assertions, *metrics, "trace"])
    for row in table["rows"]:
        found = row["verdicts"]
        verdict = [_mark(found[a]) if a in found else "" for a in assertions]
        values = [json.dumps(row["params"][n]) if isinstance(row["params"][n], list | dict) else row["params"][n]
                  for n in names]  # fmt: skip
        cells = [json.dumps(row["metrics"][m]) if isinstance(row["metrics"][m], list) else row["metrics"][m]
                 for m in metrics]  # fmt: skip
        w.writerow([row["case"], *values, row["variant"], row["backend"], row["status"], row["passed"],
                    row["failed"], *verdict, *["" if c is None else c for c in cells], row["trace"] or ""])  # fmt: skip
    return buf.getvalue()


def _print(out: Console, table: dict[str, Any], folder: Path, svg: bool, quiet: bool) -> None:
    rows = table["rows"]
    if not quiet:
        t = Table(title=f"sweep of {escape(str(table['file']))}", title_justify="left")
        for col in [*table["parameters"], "variant", "backend", "status", "assertions", *table["metrics"]]:
            t.add_column(col.removeprefix("params."), overflow="fold")
        for row in rows:
            status = row["status"] if row["status"] != "passed" else "[green]passed[/]"
            metrics = [_short(row["metrics"][m]) for m in table["metrics"]]
            t.add_row(*(escape(_short(row["params"][n])) for n in table["parameters"]), row["variant"], row["backend"],
                      status, f"{row['passed']}/{row['passed'] + row['failed']}", *metrics)  # fmt: skip
        out.print(t)
    passed = sum(r["status"] == "passed" for r in rows)
    plot = f", plot: {folder / 'sweep.svg'}" if svg else ""
    files = f"table: {folder / 'sweep.csv'}, {folder / 'sweep.json'}{plot}"
    out.print(f"[bold]{passed}/{len(rows)} cases passed[/]; {escape(files)}")


def _short(v: Any) -> str:
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def _numeric(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def plot(table: dict[str, Any]) -> str:
    """An SVG (reports.charts): one panel per numeric metric (or the share of assertions passed) against the first
    numeric parameter, one line per combination of the other parameters, variant and backend. '' if none is
    numeric."""
    from reports.charts import render
    from reports.charts.specs import Series, line_chart, stack
    from reports.charts.style import look

    rows = table["rows"]
    xs = [n for n in table["parameters"] if all(_numeric(r["params"][n]) for r in rows)]
    if not xs or not rows:
        return ""
    x = xs[0]
    panels = [m for m in table["metrics"] if any(_numeric(r["metrics"][m]) for r in rows)] or ["assertions passed"]
    series: dict[str, list[tuple[float, dict[str, Any]]]] = {}
    for r in rows:
        rest = ", ".join(f"{n.removeprefix('params.')}={r['params'][n]}" for n in table["parameters"] if n != x)
        key = " · ".join(s for s in (rest, r["variant"], r["backend"]) if s)
        series.setdefault(key or "all", []).append((float(r["params"][x]), r))
    charts = []
    for name in panels:

        def value(r: dict[str, Any], name: str = name) -> float | None:
            if name == "assertions passed":
                total = r["passed"] + r["failed"]
                return r["passed"] / total if total else None
            v = r["metrics"][name]
            return float(v) if _numeric(v) else None

        lines = []
        for c, (key, pts) in enumerate(series.items()):
            ordered = sorted(pts, key=lambda p: p[0])
            lines.append(Series(key, [p for p, _ in ordered], [value(r) for _, r in ordered], look(c)))
        y_title = "share of assertions passed (0 to 1)" if name == "assertions passed" else f"{name} (metric value)"
        charts.append(line_chart(name, lines, x_title=x.removeprefix("params."), y_title=y_title, interactive=False,
                                 legend_title="case", height=200))  # fmt: skip
    return render.svg(stack(f"{table['file']}: sweep over {x.removeprefix('params.')}", charts))
