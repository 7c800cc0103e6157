"""report.html: one self-contained page that works offline and makes no request.

At the top, the verdict in words (assertions and agreement apart, reports.headline), the engines that
depart (with the documented cause the data show) and the splits, and a matrix of variants x backends;
per case, a section of about two screens: runs, how every engine compares with the truth (stated values,
analytic references, joint constraints), then how the engines compare with each other where no truth is
known (or with the engine named by --reference), pictures of the moments
that matter, and, collapsed, the side-by-side 3D replay, the charts, trajectories, events and sounds,
every verdict, engines and cost.

Pictures are PNG (static: they show without JavaScript, in mail too). Charts are Vega-Lite specs drawn by
Vega-Embed when they come into view; the Vega bundle and the specs are inlined gzipped and inflated by
the page itself (reports/assets/report.js). Links to the traces and the Foxglove layout are relative.
"""

from __future__ import annotations

import base64
import gzip
import json
import math
from html import escape
from importlib.resources import files
from typing import Any

from reports import html_case as hc
from reports.audio import trace_audio
from reports.charts import render
from reports.charts.style import looks as make_looks
from reports.headline import amount as fmt_amount
from reports.html_charts import deviation_charts, event_charts, trajectory_charts
from reports.report_files import HTML_MARK
from reports.runs import Run
from reports.scene_pictures import CasePictures

__all__ = ["render_html"]

LAYOUT_NAME = "foxglove-layout.json"


def _asset(name: str) -> str:
    return files("reports").joinpath("assets", name).read_text(encoding="utf-8")


def _gz(text: str) -> str:
    return base64.b64encode(gzip.compress(text.encode("utf-8"), compresslevel=9, mtime=0)).decode("ascii")


def _overview(doc: dict[str, Any]) -> str:
    backends = doc["backends"]
    out = ['<table class="overview"><tr><th>variant</th><th>verdict</th>',
           *(f"<th>{escape(b)}</th>" for b in backends), "</tr>"]  # fmt: skip
    for i, case in enumerate(doc["cases"]):
        h = case["headline"]
        runs = {r["backend"]: r for r in case["runs"]}
        out.append(f'<tr><th><a href="#case-{i}">{escape(case["variant"])}</a></th>'
                   f'<td>{hc.badge(h["badge"] == "PASS", h["badge"])} {escape(h["text"])}</td>')  # fmt: skip
        for b in backends:
            r = runs.get(b)
            if r is None:
                out.append('<td class="muted">–</td>')
                continue
            a = r["assertions"]
            ok = r["status"] == "passed"
            first = r["agreement"]["first_over"]
            agree = "agrees" if not r["agreement"]["diverging"] else f"{hc.agreement_word(case, b)} from {first:g} s"
            label = f"{a['passed']}/{a['total']}" if ok else r["label"]
            out.append(f'<td><span class="{"ok" if ok else "bad"}">{"✓" if ok else "✗"} {escape(label)}</span> · '
                       f'<span class="{"ok" if not r["agreement"]["diverging"] else "bad"}">{agree}</span></td>')
        out.append("</tr>")
    out.append("</table>")
    return "".join(out)


def _thresholds(doc: dict[str, Any]) -> str:
    t, u = doc["thresholds"], doc["units"]
    angle = f"{t['angle']:g} {u['angle']} ({math.degrees(t['angle']):.3g}°)"
    limit = (f" · <b>--max-divergence {doc['max_divergence']:g} m</b> (positions; a run beyond it fails)"
             if doc["max_divergence"] is not None else "")  # fmt: skip
    return f"thresholds: positions {t['position']:g} {u['position']}, angles {angle}{limit}"


def _case(doc: dict[str, Any], case: dict[str, Any], index: int, runs: dict[str, Run], pictures: CasePictures,
          links: dict[str, str | None], charts: dict[str, Any]) -> str:  # fmt: skip
    backends = [r["backend"] for r in case["runs"]]
    looks = make_looks(doc["backends"])
    h = case["headline"]
    prefix = f"c{index}"
    end = max([r["end_time"] or 0.0 for r in case["runs"]] + [case["duration"] or 0.0])
    dev = deviation_charts(case, looks, prefix)
    traj = trajectory_charts(case, looks, prefix, _joint_kinds(runs))
    ev = event_charts(case, looks, prefix, end)
    charts.update(dev)
    charts.update(traj)
    charts.update(ev)
    known, against_ref = hc.quantity_tables(case, backends)
    stated = hc.stated_table(case, backends)
    meta = (f"{escape(case['scenario'])} · {escape(str(case['scenario_file']))} · {_dt_text(case['dt'])} · "
            f"{end:g} s simulated · {'reference' if doc['comparison'] == 'reference' else 'events matched against'} "
            f"<b>{escape(str(case['reference']))}</b>")  # fmt: skip
    parts = [
        f'<section class="case" id="case-{index}"><h2>{escape(case["variant"])} '
        f'{hc.badge(h["badge"] == "PASS", h["badge"])}<span class="headline">{escape(h["text"])}</span></h2>',
        _agreement_list(h),
        f'<p class="meta">{meta}</p>',
        hc.runs_table(case, looks, links),
        "<h3>Against the truth: values the scenario states and what the joints allow (every engine)</h3>"
        if stated or known else "",
        stated, known,
        f"<h3>{_unknown_title(doc, case)}, where no truth is known</h3>" if against_ref else "",
        against_ref,
        "<h3>Moments</h3>",
        hc.moments_html(case, pictures),
    ]  # fmt: skip
    if pictures.replay is not None:
        parts.append(f"<details class='replay'><summary>3D replay: {escape(', '.join(pictures.replay.backends))} "
                     f"side by side (time slider, play)</summary>{hc.replay_html(case, pictures, index)}</details>")
    parts.append(_charts_details("Deviation over time", dev, open_=any(q["diverging"] for q in case["quantities"])))
    parts.append(_charts_details("Trajectories", traj))
    parts.append(f"<details><summary>Events and sounds</summary>{_divs(ev)}{hc.events_table(case)}"
                 f"{_audio(runs)}</details>")  # fmt: skip
    parts.append(f"<details><summary>Every verdict</summary>{hc.verdict_matrix(case, backends)}</details>")
    parts.append(f"<details><summary>Engines and cost</summary>{hc.engines_table(case)}</details>")
    parts.append("</section>")
    return "".join(parts)


def _unknown_title(doc: dict[str, Any], case: dict[str, Any]) -> str:
    if doc["comparison"] == "reference":
        return f"Against {escape(str(case['reference']))}'s run"
    return "The engines compared with each other (groups that agree within the threshold; a majority names who departs)"


def _agreement_list(h: dict[str, Any]) -> str:
    """The departures (with their documented causes) and the splits of the headline, one line each."""
    g = h["agreement"]
    items = []
    for d in g["departures"]:
        c = d.get("cause")
        cause = ""
        if c:
            cause = (f" — {escape(c['body'])} {fmt_amount(c['measured'], 'm')} off its joint: the sag ERP "
                     f"{c['erp']:g} / CFM {c['cfm']:g} predict for {c['load']:.4g} N at h = {c['h']:g} s is "
                     f"{fmt_amount(c['predicted'], 'm')} (± {c['margin']:.0%}); <code>{escape(c['link'])}</code>")
        items.append(f'<li class="departure" data-backend="{escape(d["backend"])}"><b>{escape(d["backend"])}</b> '
                     f"departs from {escape(', '.join(d['majority']))} from {d['from']:g} s, up to "
                     f"{fmt_amount(d['max'], d['unit'])} ({escape(', '.join(d['quantities']))}){cause}</li>")
    for s in g["no_majority"]:
        where = f"{escape(s['case'])}: " if "case" in s else ""
        groups = " | ".join(", ".join(x) for x in s["groups"])
        items.append(f'<li class="split">{where}no majority on {escape(s["label"])} from {s["from"]:g} s: '
                     f"{escape(groups)}</li>")
    for d in g["diverges"]:
        items.append(f'<li class="diverges"><b>{escape(d["backend"])}</b> diverges from {escape(d["reference"])}\'s '
                     f"run by up to {fmt_amount(d['max'], d['unit'])} ({escape(', '.join(d['quantities']))})</li>")
    for d in g["misses"]:
        items.append(f'<li class="miss"><b>{escape(d["backend"])}</b> misses the truth by up to '
                     f"{fmt_amount(d['max'], d['unit'])} ({escape(', '.join(d['quantities']))})</li>")
    return f'<ul class="agreement">{"".join(items)}</ul>' if items else ""


def _joint_kinds(runs: dict[str, Run]) -> dict[str, str]:
    from reports import trace_format as tf

    for run in runs.values():
        if run.trace is not None:
            try:
                specs = json.loads(run.trace.scenario.get(tf.KEY_JOINT_SPECS, "[]"))
            except json.JSONDecodeError:
                return {}
            return {str(s.get("name")): str(s.get("kind")) for s in specs if isinstance(s, dict)}
    return {}


def _divs(charts: dict[str, Any]) -> str:
    return "".join(f'<div class="chart" data-spec="{escape(k)}"></div>' for k in charts)


def _charts_details(title: str, charts: dict[str, Any], open_: bool = False) -> str:
    if not charts:
        return ""
    hint = "drag to pan, wheel to zoom, double-click to reset; click a legend entry to show one backend"
    return (f"<details{' open' if open_ else ''}><summary>{title} ({len(charts)} charts)</summary>"
            f'<p class="muted">{hint}</p><div class="charts">{_divs(charts)}</div>'
            '<noscript>The charts need JavaScript; report.md and its images are the static version.</noscript>'
            "</details>")  # fmt: skip


def _audio(runs: dict[str, Run]) -> str:
    out = []
    for backend, run in runs.items():
        wav = trace_audio(run.trace) if run.trace is not None else None
        if wav is None:
            continue
        data = base64.b64encode(wav).decode()
        out.append(f'<figure><figcaption>{escape(backend)}</figcaption><audio controls preload="metadata" '
                   f'src="data:audio/wav;base64,{data}"></audio></figure>')  # fmt: skip
    return f'<div class="audio">{"".join(out)}</div>' if out else '<p class="muted">No sound played.</p>'


def _dt_text(dt: float | None) -> str:
    return f"dt {dt:g} s" if dt is not None else "no run reached its first step"


def render_html(doc: dict[str, Any], runs: list[Run], pictures: list[CasePictures],
                links: list[dict[str, str | None]], layout: str | None, extra: str = "") -> str:  # fmt: skip
    """The page for ``doc``; ``pictures`` and ``links`` (backend -> relative trace path) per case, ``layout``
    the relative path of the Foxglove layout beside the traces (None if there is none); ``extra``: sections
    after the cases' (how each engine imported the robots, reports.imports_render)."""
    by_key = {r.key: r for r in runs}
    title = "Backend comparison: " + ", ".join(dict.fromkeys(c["scenario"] for c in doc["cases"]))
    charts: dict[str, Any] = {}
    sections = []
    for i, case in enumerate(doc["cases"]):
        case_runs = {r["backend"]: by_key[(case["scenario"], case["variant"], r["backend"])]
                     for r in case["runs"] if (case["scenario"], case["variant"], r["backend"]) in by_key}  # fmt: skip
        sections.append(_case(doc, case, i, case_runs, pictures[i], links[i], charts))
    h = doc["headline"]
    s = doc["summary"]
    elsewhere = (f"against <b>{escape(doc['reference'])}</b>'s run elsewhere" if doc["comparison"] == "reference"
                 else "compared with the other engines elsewhere (no engine is the truth)")
    truth = ("each engine is measured against the truth where one is known (stated values, joint constraints, "
             f"analytic references) and {elsewhere}")  # fmt: skip
    layout_link = (f' · <a href="{escape(layout)}">Foxglove layout</a> (open a trace in Foxglove, then import it)'
                   if layout else "")  # fmt: skip
    specs = json.dumps(charts, separators=(",", ":"), sort_keys=True, allow_nan=False)
    gate = " and --max-divergence" if doc["max_divergence"] is not None else ""
    gate += "; the engines must agree (--require-agreement)" if doc["require_agreement"] else ""
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">{HTML_MARK}'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f'<link rel="icon" href="data:,"><title>{escape(title)}</title><style>{_asset("report.css")}</style></head>'
        f"<body><h1>{escape(title)}</h1>"
        f'<p class="verdict">{hc.badge(h["badge"] == "PASS", h["badge"])}<span class="headline" id="headline">'
        f'{escape(h["text"])}</span></p>{_agreement_list(h)}'
        f'<p class="meta">{s["ok"]}/{s["runs"]} runs pass their assertions{gate} · '
        f"{h['agreement']['quantities']} quantities compared, {h['agreement']['diverging']} beyond their threshold · "
        f"{truth} · {_thresholds(doc)}{layout_link} · "
        f'<span class="muted">{escape(doc["generator"])}, report format {doc["report_format"]}, '
        f"charts by Vega {escape(render.versions()['vega'])}</span></p>"
        f"{_overview(doc)}{''.join(sections)}{extra}"
        f'<script type="application/octet-stream" id="vega-runtime">{render.runtime_gzip_base64()}</script>'
        f'<script type="application/octet-stream" id="chart-specs">{_gz(specs)}</script>'
        f"<script>{_asset('report.js')}</script></body></html>\n"
    )
