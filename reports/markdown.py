"""report.md: the short form, for a pull-request comment or an e-mail (GitHub-flavoured markdown), with
the static pictures it shows written beside it in ``report-images/`` (PNG: the scene at the moments that
matter, and a chart of each case's most diverging quantity)."""

from __future__ import annotations

import math
import re
from typing import Any
from urllib.parse import quote, unquote

from reports.charts import render
from reports.charts.specs import Rule, Series, line_chart
from reports.charts.style import looks as make_looks
from reports.headline import amount
from reports.html_case import agreement_word, groups_text
from reports.html_charts import quantity_axis, truth_name
from reports.markdown_text import text
from reports.report_files import IMAGES_DIR, MD_MARK
from reports.scene_pictures import CasePictures

__all__ = ["IMAGES_DIR", "MAX_LINES", "markdown_images", "render_markdown", "text"]

MAX_LINES = 20
PICTURES_PER_CASE = 4


def _num(v: float | None, unit: str = "") -> str:
    if v is None or not math.isfinite(v):
        return "–"
    text = f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}"
    return f"{text} {unit}".strip()


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-") or "case"


def _worst(case: dict[str, Any]) -> dict[str, Any] | None:
    ranked = [(max((d["max"] or 0.0) for d in q["deviation"].values()) / q["threshold"], k, q)
              for k, q in enumerate(case["quantities"]) if q["deviation"] and q["threshold"]]  # fmt: skip
    return max(ranked, key=lambda r: (r[0], -r[1]))[2] if ranked else None


def markdown_images(doc: dict[str, Any], pictures: list[CasePictures]) -> dict[str, bytes]:
    """File name -> PNG bytes of every image report.md shows."""
    out: dict[str, bytes] = {}
    looks = make_looks(doc["backends"])
    for i, (case, pics) in enumerate(zip(doc["cases"], pictures, strict=True)):
        stem = f"{i:02d}-{_slug(case['variant'])}"
        for k, groups in enumerate(pics.pictures):
            for p in groups:
                out[f"{stem}-m{k}-{_slug('+'.join(p.backends))}.png"] = p.png
        q = _worst(case)
        if q is not None:
            series = [Series(b, s["t"], s["deviation"], looks[b]) for b, s in q["series"].items()]
            spec = line_chart(f"{case['variant']}: {q['label']}, deviation from {truth_name(q)}", series,
                              y_title=quantity_axis(q), rules=[Rule(q["threshold"], f"threshold {q['threshold']:g}"
                              f" {q['unit']}")], interactive=False, width=560, height=180)  # fmt: skip
            out[f"{stem}-deviation.png"] = render.png(spec)
    return out


def _case_pictures(i: int, case: dict[str, Any], images: dict[str, bytes]) -> list[str]:
    stem = f"{i:02d}-{_slug(case['variant'])}"
    shots = []
    moments = case["key_moments"]
    chosen = [k for k, m in enumerate(moments) if 0 < k < len(moments) - 1][: PICTURES_PER_CASE - 1]
    chosen = sorted(set(chosen + [len(moments) - 1])) if moments else []
    for k in chosen:
        names = sorted(n for n in images if n.startswith(f"{stem}-m{k}-"))
        for name in names:
            who = name[len(f"{stem}-m{k}-") : -4].replace("+", ", ")
            shots.append(f"![{text(case['variant'])}, t = {moments[k]['t']:g} s, {text(who)}]"
                         f"(./{IMAGES_DIR}/{quote(name)})")  # fmt: skip
    if f"{stem}-deviation.png" in images:
        shots.append(f"![{text(case['variant'])}\\: deviation over time](./{IMAGES_DIR}/{quote(stem)}-deviation.png)")
    return shots


def _agreement_lines(h: dict[str, Any]) -> list[str]:
    """The departures with their documented causes, one bullet each (the headline's words say the rest)."""
    out = []
    for d in h["agreement"]["departures"]:
        c = d.get("cause")
        if c:
            out.append(f"- **{text(d['backend'])}** departs: {text(c['body'])} {amount(c['measured'], 'm')} off "
                       f"its joint, the sag ERP {c['erp']:g} / CFM {c['cfm']:g} predict for {c['load']:.4g} N at "
                       f"h = {c['h']:g} s: "
                       f"{amount(c['predicted'], 'm')} (± {c['margin']:.0%}); see {text(c['link'])}")  # fmt: skip
    return ["", *out] if out else []


def render_markdown(doc: dict[str, Any], images: dict[str, bytes], links: list[dict[str, str | None]],
                    layout: str | None) -> str:  # fmt: skip
    backends = doc["backends"]
    h, s, t = doc["headline"], doc["summary"], doc["thresholds"]
    scenarios = ", ".join(text(s) for s in dict.fromkeys(c["scenario"] for c in doc["cases"]))
    limit = f"; `--max-divergence` {doc['max_divergence']:g} m" if doc["max_divergence"] is not None else ""
    limit += "; `--require-agreement`" if doc["require_agreement"] else ""
    elsewhere = (f"against **{text(doc['reference'])}**'s run elsewhere" if doc["comparison"] == "reference" else
                 "compared with the other engines elsewhere (no engine is the truth: a majority names the engines "
                 "that depart)")  # fmt: skip
    out = [
        f"{MD_MARK} {scenarios} — {'✅ PASS' if h['badge'] == 'PASS' else '❌ FAIL'}: {text(h['text'])}",
        "",
        f"{s['ok']}/{s['runs']} runs pass their assertions. Each engine is measured against the truth where one is "
        f"known (values the assertions state, joint constraints, analytic references) and {elsewhere}. Thresholds: "
        f"positions {t['position']:g} m, angles {t['angle']:.3g} rad ({math.degrees(t['angle']):.3g}°){limit}.",
        *_agreement_lines(h),
        "",
        "| variant | verdict | " + " | ".join(text(b) for b in backends) + " |",
        "|---|---|" + "---|" * len(backends),
    ]  # fmt: skip
    lines: list[str] = []
    for case in doc["cases"]:
        runs = {r["backend"]: r for r in case["runs"]}
        cells = []
        for b in backends:
            r = runs.get(b)
            if r is None:
                cells.append("–")
                continue
            a = r["assertions"]
            ok = r["status"] == "passed"
            first = r["agreement"]["first_over"]
            agree = "agrees" if not r["agreement"]["diverging"] else f"{agreement_word(case, b)} from {first:g} s"
            limits = (
                f", ⚠️ {a['known_limits']} known limit{'s' * (a['known_limits'] > 1)}" if a.get("known_limits") else ""
            )
            cells.append(f"{'✅' if ok else '❌'} {a['passed']}/{a['total']}{limits}"
                         f"{'' if ok else ' ' + text(r['label'])} · {text(agree)}")  # fmt: skip
            for name in case["verdicts"]["assertions"]:
                v = case["verdicts"]["cells"][name].get(b)
                if v is not None and v.get("status") == "known limit":
                    lines.append(f"- {text(case['variant'])} · {text(b)}: **{text(name)}** ⚠️ {text(v['message'])}")
                elif v is not None and v["passed"] is not True:
                    lines.append(f"- {text(case['variant'])} · {text(b)}: **{text(name)}** measured "
                                 f"{text(v['measured'])}, expected {text(v['expected'])}")  # fmt: skip
            if r["outcome"] is not None or r["status"] not in ("passed", "failed"):
                detail = f": {r['detail'][:200]}" if r["detail"] else ""
                lines.append(f"- {text(case['variant'])} · {text(b)}: {text(r['label'])}{text(detail)}")
        ch = case["headline"]
        mark = "✅" if ch["badge"] == "PASS" else "❌"
        out.append(f"| {text(case['variant'])} | {mark} {text(ch['text'])} | " + " | ".join(cells) + " |")
        for q in case["quantities"]:
            verdict = q.get("agreement")
            if verdict is not None and (q["diverging"] or verdict["no_majority_from"] is not None):
                who = "; ".join(f"{text(d['backend'])} departs from {text(', '.join(d['majority']))} from "
                                f"{d['from']:g} s, up to {text(_num(d['max'], q['unit']))}"
                                for d in verdict["departures"])  # fmt: skip
                split = (f"no majority from {verdict['no_majority_from']:g} s"
                         if verdict["no_majority_from"] is not None else "")  # fmt: skip
                lines.append(f"- {text(case['variant'])} · **{text(q['label'])}** (engines compared, threshold "
                             f"{q['threshold']:g} {text(q['unit'])}; groups {text(groups_text(q))}): "
                             f"{'; '.join(x for x in (who, split) if x)}")  # fmt: skip
            elif q["diverging"]:
                who = ", ".join(f"{text(b)} {text(_num(q['deviation'][b]['max'], q['unit']))}"
                                for b in q["diverging"])  # fmt: skip
                lines.append(f"- {text(case['variant'])} · **{text(q['label'])}** (against {text(truth_name(q))}, "
                             f"threshold {q['threshold']:g} {text(q['unit'])}): {who}, "
                             f"from {q['first_over']:g} s")  # fmt: skip
    if lines:
        out += ["", "### Problems and divergences", ""]
        out += lines[:MAX_LINES]
        if len(lines) > MAX_LINES:
            out.append(f"- … and {len(lines) - MAX_LINES} more (see report.html)")
    pics = [(case, _case_pictures(i, case, images)) for i, case in enumerate(doc["cases"])]
    if any(shots for _, shots in pics):
        out += ["", "### Pictures", ""]
        for case, shots in pics:
            if shots:
                out += [f"**{text(case['variant'])}**", "", " ".join(shots), ""]
    out += ["", "### Cost (sum over cases)", "", "| backend | engine | wall time (s) | steps/s | real-time factor |",
            "|---|---|---|---|---|"]  # fmt: skip
    for b in backends:
        of_b = [r for c in doc["cases"] for r in c["runs"] if r["backend"] == b]
        known = [r for r in of_b if r["cost"]["wall_seconds"]]
        wall = sum(r["cost"]["wall_seconds"] for r in known) if known else None
        steps = sum(r["cost"]["steps"] for r in known)
        sim = sum(r["cost"]["simulated_seconds"] or 0.0 for r in known)
        version = of_b[0]["engine_version"] if of_b else ""
        out.append(f"| {text(b)} | {text(version)} | {_num(wall)} | {_num(steps / wall if wall else None)} | "
                   f"{_num(sim / wall if wall else None)} |")  # fmt: skip
    traces = sorted({v for case_links in links for v in case_links.values() if v})
    out += ["", f"Traces ({len(traces)}): " + ", ".join(f"[{text(unquote(p.rsplit('/', 1)[-1]))}]({p})"
                                                    for p in traces[:8])  # fmt: skip
            + (" …" if len(traces) > 8 else "") + (f" · [Foxglove layout]({layout})" if layout else ""),
            "", "Full report with interactive charts, the 3D replay and sounds: `report.html`; data: `report.json`.",
            ""]  # fmt: skip
    return "\n".join(out)
