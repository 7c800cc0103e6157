"""One case of the HTML report: headline, runs, the truth tables, the moments, the replay, then the details
(collapsed): charts, trajectories, events and sounds, every verdict, engines and cost."""

from __future__ import annotations

import base64
import json
import math
from html import escape
from typing import Any

from reports.charts.style import Look
from reports.html_charts import truth_name
from reports.scene_pictures import HEIGHT, WIDTH, CasePictures

__all__ = ["agreement_word", "badge", "fmt", "groups_text", "key", "moments_html", "replay_html", "runs_table",
           "stated_table", "quantity_tables", "verdict_matrix", "events_table", "engines_table"]  # fmt: skip

GAP = 8


def fmt(v: float | None, unit: str = "", digits: int = 3) -> str:
    if v is None or not math.isfinite(v):
        return "–"
    text = "0" if v == 0 else f"{v:.{digits}g}"
    return f"{text} {unit}".strip()


def badge(ok: bool, text: str) -> str:
    return f'<span class="badge {"ok" if ok else "bad"}">{escape(text)}</span>'


def key(look: Look) -> str:
    """A small sample of a backend's line: its colour and dash."""
    dash = " ".join(str(d) for d in look.dash)
    return (f'<svg class="key" viewBox="0 0 26 10" aria-hidden="true"><line x1="1" y1="5" x2="25" y2="5" '
            f'stroke="{look.color}" stroke-width="2.5" stroke-dasharray="{dash}"/></svg>')  # fmt: skip


def _worst(case: dict[str, Any], backend: str) -> tuple[dict[str, Any], float] | None:
    worst = None
    for q in case["quantities"]:
        d = q["deviation"].get(backend)
        if d is None or d["max"] is None or not q["threshold"]:
            continue
        ratio = d["max"] / q["threshold"]
        if worst is None or ratio > worst[1]:
            worst = (q, ratio)
    return worst


def agreement_word(case: dict[str, Any], backend: str) -> str:
    """How a run that is named on some quantity strays: it departs from a majority of the engines, misses a
    known truth, or diverges from the reference engine's run."""
    kinds = {q["truth"]["kind"] for q in case["quantities"] if backend in q["diverging"]}
    words = [w for k, w in (("engines", "departs"), ("reference", "diverges")) if k in kinds]
    if kinds - {"engines", "reference"}:
        words.insert(0, "misses the truth")
    return " and ".join(words) or "agrees"


def groups_text(q: dict[str, Any]) -> str:
    """The groups of engines that agree on ``q`` at the end (a majority first), e.g. "dart, mujoco | ode"."""
    return " | ".join(", ".join(g) for g in q["agreement"]["groups"])


def runs_table(case: dict[str, Any], looks: dict[str, Look], links: dict[str, str | None]) -> str:
    head = ("backend", "run", "assertions", "agreement", "largest deviation / threshold", "trace", "wall time")
    named = any(q["truth"]["kind"] == "reference" for q in case["quantities"])  # --reference: the runs' yardstick
    reference = case["reference"] if named else None
    out = ['<table class="runs"><tr>', *(f"<th>{h}</th>" for h in head), "</tr>"]
    for r in case["runs"]:
        b, a = r["backend"], r["assertions"]
        run_ok = r["status"] == "passed"
        status = f'<span class="{"ok" if run_ok else "bad"}">{escape(r["label"])}</span>'
        if r["detail"] and not run_ok:
            status += f'<div class="muted">{escape(r["detail"][:240])}</div>'
        assertions = f'<span class="{"ok" if not a["failed"] else "bad"}">{a["passed"]}/{a["total"]} pass</span>'
        if a.get("known_limits"):
            assertions += f' <span class="close">{a["known_limits"]} known limit{"s" * (a["known_limits"] > 1)}</span>'
        div = r["agreement"]["diverging"]
        if div:
            labels = [q["label"] for q in case["quantities"] if q["id"] in div]
            agree = f'<span class="bad">{agreement_word(case, b)} from ' \
                    f'{fmt(r["agreement"]["first_over"], "s")}</span>: {escape(", ".join(labels))}'  # fmt: skip
        else:
            agree = '<span class="ok">within thresholds</span>'
        if r["within_max_divergence"] is False:
            agree += ' <span class="bad">(over --max-divergence)</span>'
        worst = _worst(case, b)
        worst_txt = "–"
        if worst is not None:
            q, ratio = worst
            d = q["deviation"][b]
            cls = "bad" if ratio > 1 else "ok"
            worst_txt = (f'<span class="{cls}">{fmt(d["max"], q["unit"])} / {fmt(q["threshold"], q["unit"])}</span> '
                         f'{escape(q["label"])} at {fmt(d["max_time"], "s")}')  # fmt: skip
        link = links.get(b)
        trace = f'<a href="{escape(link)}">{escape(r["trace"] or "")}</a>' if link else escape(r["trace"] or "–")
        out.append(
            f"<tr><td>{key(looks[b])}<b>{escape(b)}</b>{' (reference)' if b == reference else ''}</td>"
            f"<td>{status}</td><td>{assertions}</td><td>{agree}</td><td>{worst_txt}</td><td>{trace}</td>"
            f'<td class="num">{fmt(r["cost"]["wall_seconds"], "s")}</td></tr>'
        )
    out.append("</table>")
    return "".join(out)


def _expected(cell: dict[str, Any]) -> str:
    if cell["target"] is not None:
        return f"{fmt(cell['target'], digits=6)} ± {fmt(cell['tolerance'])}"
    lo = "−∞" if cell["lo"] is None else fmt(cell["lo"], digits=6)
    hi = "∞" if cell["hi"] is None else fmt(cell["hi"], digits=6)
    return f"in [{lo}, {hi}]"


def stated_table(case: dict[str, Any], backends: list[str]) -> str:
    rows = case["stated"]
    if not rows:
        return ""
    out = ['<table class="stated"><tr><th>assertion</th><th>stated value</th>',
           *(f"<th>{escape(b)}</th>" for b in backends), "</tr>"]  # fmt: skip
    for row in rows:
        cells = row["cells"]
        any_cell = next(iter(cells.values()))
        out.append(f"<tr><th>{escape(row['name'])}</th><td class='num'>{escape(_expected(any_cell))}</td>")
        for b in backends:
            c = cells.get(b)
            if c is None:
                out.append('<td class="muted">–</td>')
                continue
            close = c["tolerance"] and c["passed"] and abs(c["deviation"]) > 0.75 * c["tolerance"]
            cls = "bad" if not c["passed"] else "close" if close else ""
            dev = f"{c['deviation'] + 0.0:+.3g}" if c["target"] is not None else fmt(c["deviation"])
            tip = f"measured {c['measured']:.9g}" + (f" at t = {c['time']:g} s" if c["time"] is not None else "")
            out.append(f'<td class="num {cls}" title="{escape(tip)}">{fmt(c["measured"], digits=5)} '
                       f'<span class="muted">({escape(dev)})</span></td>')  # fmt: skip
        out.append("</tr>")
    out.append("</table>")
    return "".join(out)


def _judged(q: dict[str, Any]) -> str:
    """What the engines concluded on a quantity without a truth: the groups, who departs, no majority."""
    a = q["agreement"]
    said = [escape(groups_text(q))]
    for d in a["departures"]:
        said.append(f'<span class="bad">{escape(d["backend"])} departs from {fmt(d["from"], "s")}, up to '
                    f'{fmt(d["max"], q["unit"])}</span>')  # fmt: skip
    if a["no_majority_from"] is not None:
        said.append(f'<span class="close">no majority from {fmt(a["no_majority_from"], "s")}</span>')
    return "<br>".join(said)


def _quantity_rows(qs: list[dict[str, Any]], backends: list[str], reference: str | None) -> list[str]:
    out = []
    for q in qs:
        truth = q["truth"]
        source = _judged(q) if "agreement" in q else escape(truth.get("source") or truth_name(q))
        out.append(f"<tr><th>{escape(q['label'])}</th><td>{source}</td>"
                   f"<td class='num'>{fmt(q['threshold'], q['unit'])}</td>")  # fmt: skip
        for b in backends:
            d = q["deviation"].get(b)
            if d is None:
                text = "is the truth here" if truth["kind"] == "reference" and b == reference else "–"
                out.append(f'<td class="muted">{text}</td>')
                continue
            over = b in q["diverging"]
            when = f" from {fmt(d['first_over'], 's')}" if over else ""
            out.append(f'<td class="num{" bad" if over else ""}" title="largest at t = {fmt(d["max_time"], "s")}, '
                       f'RMS {fmt(d["rms"], q["unit"])}">{fmt(d["max"], q["unit"])}{when}</td>')  # fmt: skip
        out.append("</tr>")
    return out


def quantity_tables(case: dict[str, Any], backends: list[str]) -> tuple[str, str]:
    """(the quantities with a known truth, those where none is: among the engines or against the reference
    engine) as tables."""
    unknown = ("reference", "engines")
    known = [q for q in case["quantities"] if q["truth"]["kind"] not in unknown]
    ref = [q for q in case["quantities"] if q["truth"]["kind"] in unknown]
    tables = []
    for qs, what in ((known, "truth"), (ref, "engines that agree | the others")):
        if ref and qs is ref and ref[0]["truth"]["kind"] == "reference":
            what = "against"
        head = (f"<tr><th>quantity</th><th>{what}</th><th>threshold</th>"
                + "".join(f"<th>{escape(b)}</th>" for b in backends) + "</tr>")  # fmt: skip
        rows = _quantity_rows(qs, backends, case["reference"])
        tables.append(f'<table class="quantities">{head}{"".join(rows)}</table>' if rows else "")
    return tables[0], tables[1]


def moments_html(case: dict[str, Any], pictures: CasePictures) -> str:
    if not pictures.pictures:
        return f'<p class="muted">{escape(pictures.note or "No pictures.")}</p>'
    out = ['<div class="moments">']
    for moment, groups in zip(case["key_moments"], pictures.pictures, strict=True):
        shots = []
        for p in groups:
            names = "all backends" if len(groups) == 1 and len(p.backends) > 1 else ", ".join(p.backends)
            data = base64.b64encode(p.png).decode()
            bodies = escape(json.dumps(p.bodies, separators=(",", ":")))
            shots.append(f'<figure class="shot"><img class="picture" width="{WIDTH}" height="{HEIGHT}" '
                         f'alt="{escape(names)} at t = {p.t:g} s" data-t="{p.t:g}" data-backends="{escape(names)}" '
                         f'data-bodies="{bodies}" src="data:image/png;base64,{data}">'
                         f"<figcaption>{escape(names)}</figcaption></figure>")  # fmt: skip
        out.append(
            f'<figure class="moment"><div class="shots">{"".join(shots)}</div><figcaption>'
            f"<b>t = {moment['t']:g} s</b> · {escape('; '.join(moment['reasons']))}</figcaption></figure>"
        )
    out.append("</div>")
    return "".join(out)


def replay_html(case: dict[str, Any], pictures: CasePictures, index: int) -> str:
    r = pictures.replay
    if r is None:
        return ""
    data = {"times": r.times, "backends": r.backends, "w": WIDTH, "h": HEIGHT, "gap": GAP, "bodies": r.body_names,
            "colours": r.colours, "centres": r.bodies}  # fmt: skip
    text = json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")
    sheet = base64.b64encode(r.png).decode()
    width = len(r.backends) * (WIDTH + GAP) - GAP
    labels = "".join(f'<span style="width:{WIDTH}px">{escape(b)}</span>' for b in r.backends)
    moments = "".join(f'<button class="moment" data-t="{m["t"]:g}" title="{escape(m["label"])}">{m["t"]:g} s</button>'
                      for m in case["key_moments"])  # fmt: skip
    return (
        f'<div class="replay" id="replay-{index}" data-sheet="data:image/png;base64,{sheet}">'
        f'<div class="panels">{labels}</div><canvas width="{width}" height="{HEIGHT}"></canvas>'
        f'<div class="controls"><button class="play">▶ play</button>'
        f'<button class="wide" aria-pressed="false" title="show the replay as wide as the page">⤢ full width</button>'
        f'<input type="range" min="0" max="{len(r.times) - 1}" step="1" value="0" aria-label="time">'
        f'<span class="clock">t = 0.00 s</span><span class="muted">moments:</span>{moments}</div>'
        f'<script type="application/json" class="replay-data">{text}</script></div>'
    )


def verdict_matrix(case: dict[str, Any], backends: list[str]) -> str:
    matrix = case["verdicts"]
    if not matrix["assertions"]:
        return "<p>No verdicts were recorded.</p>"
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
            if cell.get("status") == "known limit":  # an expected failure: its figure and cause in full
                out.append(
                    f'<td title="{escape(tip)}"><span class="close">⚠ known limit</span> '
                    f'{escape(str(cell["measured"]))}<div class="muted">{escape(cell["message"])}</div></td>'
                )
                continue
            out.append(f'<td title="{escape(tip)}"><span class="{"ok" if ok else "bad"}">{"✓" if ok else "✗ FAIL"}'
                       f"</span> {escape(str(cell['measured']))}</td>")  # fmt: skip
        out.append("</tr>")
    out.append("</table>")
    return "".join(out)


def events_table(case: dict[str, Any]) -> str:
    rows = []
    for backend, items in case["events"]["comparison"].items():
        for e in items:
            flags = []
            if e["extra"]:
                flags.append("extra at " + ", ".join(f"{t:g}" for t in e["extra"]))
            if e["missing"]:
                flags.append("missing at " + ", ".join(f"{t:g}" for t in e["missing"]))
            delta = e["first_delta"]
            rows.append(
                f"<tr><td>{escape(backend)}</td><td>{escape(e['name'])}</td>"
                f"<td class='num'>{e['count']} / {e['reference_count']}</td>"
                f"<td class='num'>{fmt(e['first'], 's', 4)}</td>"
                f"<td class='num'>{fmt(e['reference_first'], 's', 4)}</td>"
                f"<td class='num'>{'–' if delta is None else f'{delta:+.3g} s'}</td>"
                f"<td class='{'ok' if e['status'] == 'match' else 'close'}'>{escape(e['status'])}</td>"
                f"<td>{escape('; '.join(flags))}</td></tr>"
            )
    if not rows:
        return ""
    head = ("backend", "event", "count / reference's", "first", "reference's first", "Δ first", "matching", "flags")
    return "<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr>" + "".join(rows) + "</table>"


def engines_table(case: dict[str, Any]) -> str:
    out = ["<table><tr><th>backend</th><th>engine</th><th>steps</th><th>simulated</th><th>wall time</th>"
           "<th>steps/s</th><th>real-time factor</th></tr>"]  # fmt: skip
    for r in case["runs"]:
        c = r["cost"]
        out.append(f"<tr><td>{escape(r['backend'])}</td><td>{escape(r['engine_version'])}</td>"
                   f"<td class='num'>{c['steps']}</td><td class='num'>{fmt(c['simulated_seconds'], 's')}</td>"
                   f"<td class='num'>{fmt(c['wall_seconds'], 's')}</td>"
                   f"<td class='num'>{fmt(c['steps_per_second'])}</td>"
                   f"<td class='num'>{fmt(c['real_time_factor'])}</td></tr>")  # fmt: skip
    out.append("</table>")
    settings = "".join(
        f"<details><summary>{escape(r['backend'])} engine settings</summary>"
        f"<pre>{escape(json.dumps(r['engine_settings'], indent=2, sort_keys=True))}</pre></details>"
        for r in case["runs"]
    )
    return "".join(out) + settings
