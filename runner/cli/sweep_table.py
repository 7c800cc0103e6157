"""`scenario sweep`'s results: the table (one row per case, written as JSON), its CSV, the terminal table and
the SVG plot of the metrics against the first numeric parameter."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table


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


def print_table(out: Console, table: dict[str, Any], folder: Path, svg: bool, quiet: bool) -> None:
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
