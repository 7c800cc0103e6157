"""report.html: one self-contained page (inline CSS, SVG and data: URIs; no script runs, no network).

The comparison document is embedded whole as ``<script type="application/json" id="report-data">`` so
the page carries its data. Per case: runs and cost, the verdict matrix, trajectories, divergence from
the reference, events, sounds (with an audio track per backend), pictures at key moments and the
side-by-side animation.
"""

from __future__ import annotations

import json
from html import escape
from typing import Any

from reports import html_figures as fig
from reports.plots import color_for
from reports.runs import Run

__all__ = ["render_html"]

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:0 auto;max-width:1500px;padding:0 24px 48px;
color:#1d232b;background:#fff}
h1{font-size:24px;margin:22px 0 6px}h2{font-size:20px;margin:36px 0 8px;border-bottom:2px solid #dde3ea;
padding-bottom:4px}h3{font-size:16px;margin:22px 0 8px}
table{border-collapse:collapse;margin:6px 0 12px;font-size:13px}th,td{border:1px solid #d5dbe2;padding:4px 8px;
text-align:left;vertical-align:top}th{background:#f1f4f7}td.num{text-align:right;font-variant-numeric:tabular-nums}
.ok{color:#156c2f;font-weight:600}.bad{color:#b3261e;font-weight:600}.muted{color:#6a737d}
.badge{display:inline-block;border-radius:10px;padding:1px 9px;font-size:12px;font-weight:600;color:#fff}
.badge.ok{background:#2e8b47;color:#fff}.badge.bad{background:#c0392b;color:#fff}
.swatch{display:inline-block;width:10px;height:10px;border-radius:2px;margin-right:6px}
.charts{display:flex;flex-wrap:wrap;gap:10px}.charts svg{border:1px solid #e3e7ec}
table.pictures td{padding:2px}table.pictures svg{display:block}
div.animation .labels{display:flex;font-size:12px;font-weight:600}div.animation img{display:block;
border:1px solid #d5dbe2}div.audio{display:flex;flex-wrap:wrap;gap:16px}figure{margin:4px 0}
nav a{margin-right:14px}details pre{font-size:11px;background:#f6f8fa;padding:6px;max-width:900px;overflow:auto}
"""


def _num(v: float | None, digits: int = 4) -> str:
    return "–" if v is None else f"{v:.{digits}g}"


def _badge(ok: bool, text: str) -> str:
    return f'<span class="badge {"ok" if ok else "bad"}">{escape(text)}</span>'


def _runs_table(doc: dict[str, Any], case: dict[str, Any]) -> str:
    colors = {b: color_for(i) for i, b in enumerate(doc["backends"])}
    head = ("backend", "status", "assertions", "max position error (m)", "max angle error (rad)",
            "max joint error", "wall time (s)", "steps/s", "real-time factor", "engine")  # fmt: skip
    out = ["<table><tr>", *(f"<th>{h}</th>" for h in head), "</tr>"]
    for r in case["runs"]:
        b = r["backend"]
        div = case["divergence"].get(b)
        is_ref = b == case["reference"]
        if is_ref:
            errs = ['<td colspan="3" class="muted">reference</td>']
        elif div and div.get("available"):
            errs = [f'<td class="num">{_num(div["max"][k])}</td>' for k in ("position", "angle", "joint")]
        else:
            reason = div.get("reason", "") if div else ""
            errs = [f'<td colspan="3" class="muted">{escape(reason)}</td>']
        a = r["assertions"]
        label = r["label"] + ("" if r["within_max_divergence"] is not False else " · diverged")
        status = _badge(r["ok"], label)
        if r["detail"]:
            status += f'<div class="muted">{escape(r["detail"][:300])}</div>'
        c = r["cost"]
        out.append(
            f'<tr><td><span class="swatch" style="background:{colors[b]}"></span>{escape(b)}</td><td>{status}</td>'
            f'<td class="num">{a["passed"]}/{a["total"]}</td>{"".join(errs)}'
            f'<td class="num">{_num(c["wall_seconds"])}</td><td class="num">{_num(c["steps_per_second"])}</td>'
            f'<td class="num">{_num(c["real_time_factor"])}</td><td>{escape(r["engine_version"])}</td></tr>'
        )
    out.append("</table>")
    settings = "".join(
        f"<details><summary>{escape(r['backend'])} {escape(r['engine_version'])}: engine settings"
        f"{' · trace ' + escape(r['trace']) if r['trace'] else ''}</summary>"
        f"<pre>{escape(json.dumps(r['engine_settings'], indent=2, sort_keys=True))}</pre></details>"
        for r in case["runs"]
    )
    return "".join(out) + settings


def _verdict_matrix(case: dict[str, Any]) -> str:
    matrix = case["verdicts"]
    if not matrix["assertions"]:
        return "<p>No verdicts were recorded.</p>"
    backends = [r["backend"] for r in case["runs"]]
    out = ['<table class="verdicts"><tr><th>assertion</th>', *(f"<th>{escape(b)}</th>" for b in backends), "</tr>"]
    for name in matrix["assertions"]:
        out.append(f"<tr><th>{escape(name)}</th>")
        for b in backends:
            cell = matrix["cells"][name].get(b)
            if cell is None:
                out.append('<td class="muted">not run</td>')
                continue
            ok = cell["passed"] is True
            tip = f"expected {cell['expected']}" + (f"; {cell['message']}" if cell["message"] else "")
            mark = "✓ pass" if ok else "✗ FAIL"
            out.append(f'<td title="{escape(tip)}"><span class="{"ok" if ok else "bad"}">{mark}</span> '
                       f"{escape(str(cell['measured']))}</td>")  # fmt: skip
        out.append("</tr>")
    out.append("</table>")
    return "".join(out)


def _divergence_table(case: dict[str, Any]) -> str:
    rows = []
    for backend, d in case["divergence"].items():
        if not d.get("available"):
            rows.append(f'<tr><td>{escape(backend)}</td><td colspan="6" class="muted">{escape(d["reason"])}</td></tr>')
            continue
        items = [(f"{b} position (m)", s["position"]) for b, s in d["bodies"].items()]
        items += [(f"{b} angle (rad)", s["angle"]) for b, s in d["bodies"].items()]
        items += [(f"{j} position", s) for j, s in d["joints"].items()]
        for what, s in items:
            over = s["first_over"]
            over_txt = "never" if over is None else f'<span class="bad">{over:g} s</span>'
            rows.append(
                f"<tr><td>{escape(backend)}</td><td>{escape(what)}</td><td class='num'>{_num(s['max'])}</td>"
                f"<td class='num'>{_num(s['max_time'])}</td><td class='num'>{_num(s['rms'])}</td>"
                f"<td class='num'>{s['threshold']:g}</td><td>{over_txt}</td></tr>"
            )
    if not rows:
        return ""
    head = "<tr><th>backend</th><th>value</th><th>max</th><th>at (s)</th><th>RMS</th><th>threshold</th>" \
           "<th>first over</th></tr>"  # fmt: skip
    return f"<table>{head}{''.join(rows)}</table>"


def _events_table(case: dict[str, Any]) -> str:
    rows = []
    for backend, items in case["events"]["comparison"].items():
        for e in items:
            ok = e["status"] == "match"
            flags = []
            if e["extra"]:
                flags.append("extra at " + ", ".join(f"{t:g}" for t in e["extra"]))
            if e["missing"]:
                flags.append("missing at " + ", ".join(f"{t:g}" for t in e["missing"]))
            delta = e["first_delta"]
            rows.append(
                f"<tr><td>{escape(backend)}</td><td>{escape(e['name'])}</td>"
                f"<td class='num'>{e['count']}</td><td class='num'>{e['reference_count']}</td>"
                f"<td class='num'>{_num(e['first'])}</td><td class='num'>{_num(e['reference_first'])}</td>"
                f"<td class='num'>{'–' if delta is None else f'{delta:+.4g}'}</td>"
                f"<td class='{'ok' if ok else 'bad'}'>{escape(e['status'])}</td>"
                f"<td>{escape('; '.join(flags))}</td></tr>"
            )
    if not rows:
        return ""
    head = ("backend", "event", "count", "reference count", "first (s)", "reference first (s)", "Δ first (s)",
            "status", "flags")  # fmt: skip
    return "<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>" + "".join(rows) + "</table>"


def _case(doc: dict[str, Any], case: dict[str, Any], index: int, runs: dict[str, Run]) -> str:
    ok = all(r["ok"] for r in case["runs"])
    meta = (f"reference <b>{escape(str(case['reference']))}</b> · dt {case['dt']} s · duration "
            f"{case['duration']} s · file {escape(str(case['scenario_file']))}")  # fmt: skip
    return "".join(
        [
            f'<section id="case-{index}"><h2>{escape(case["scenario"])} · {escape(case["variant"])} ',
            _badge(ok, "all pass" if ok else "not all pass"),
            f'</h2><p class="muted">{meta}</p>',
            "<h3>Runs and cost</h3>",
            _runs_table(doc, case),
            "<h3>Verdicts</h3>",
            _verdict_matrix(case),
            "<h3>Trajectories</h3>",
            f'<div class="charts">{fig.trajectory_charts(doc, case)}</div>',
            f"<h3>Divergence from {escape(str(case['reference']))}</h3>",
            _divergence_table(case) or "<p>Only the reference ran.</p>",
            f'<div class="charts">{fig.divergence_charts(doc, case)}</div>',
            "<h3>Events</h3>",
            fig.event_timeline(doc, case),
            _events_table(case),
            "<h3>Sounds</h3>",
            fig.sound_section(doc, case, runs),
            "<h3>Pictures</h3>",
            fig.pictures_html(case, runs),
            "<h3>Animation</h3>",
            fig.animation_html(case, runs),
            "</section>",
        ]
    )


def render_html(doc: dict[str, Any], runs: list[Run]) -> str:
    """The page for ``doc``, with pictures and audio drawn from ``runs`` (the runs it was built from)."""
    by_key = {r.key: r for r in runs}
    title = "Backend comparison: " + ", ".join(dict.fromkeys(c["scenario"] for c in doc["cases"]))
    nav = "".join(
        f'<a href="#case-{i}">{escape(c["variant"])} {"✓" if all(r["ok"] for r in c["runs"]) else "✗"}</a>'
        for i, c in enumerate(doc["cases"])
    )
    s = doc["summary"]
    limit = "" if doc["max_divergence"] is None else f" · max divergence {doc['max_divergence']:g}"
    sections = []
    for i, case in enumerate(doc["cases"]):
        case_runs = {
            r["backend"]: by_key[(case["scenario"], case["variant"], r["backend"])]
            for r in case["runs"]
            if (case["scenario"], case["variant"], r["backend"]) in by_key
        }
        sections.append(_case(doc, case, i, case_runs))
    data = json.dumps(doc, separators=(",", ":"), allow_nan=False, ensure_ascii=False).replace("<", "\\u003c")
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f'<link rel="icon" href="data:,"><title>{escape(title)}</title><style>{_CSS}</style></head><body>'
        f"<h1>{escape(title)}</h1>"
        f"<p>{_badge(doc['passed'], 'PASS' if doc['passed'] else 'FAIL')} {s['ok']}/{s['runs']} runs pass · "
        f"reference <b>{escape(doc['reference'])}</b> · backends {escape(', '.join(doc['backends']))}{limit} · "
        f'<span class="muted">{escape(doc["generator"])}, report format {doc["report_format"]}</span></p>'
        f"<nav>{nav}</nav>{''.join(sections)}"
        f'<script type="application/json" id="report-data">{data}</script></body></html>\n'
    )
