"""report.md: the short form, for a pull-request comment (GitHub-flavoured markdown tables)."""

from __future__ import annotations

from typing import Any

__all__ = ["render_markdown"]

MAX_FAILURES = 20


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _num(v: float | None) -> str:
    if v is None:
        return "–"
    return f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}"


def render_markdown(doc: dict[str, Any]) -> str:
    backends = doc["backends"]
    s = doc["summary"]
    limit = "" if doc["max_divergence"] is None else f", max divergence {doc['max_divergence']:g}"
    scenarios = ", ".join(dict.fromkeys(c["scenario"] for c in doc["cases"]))
    out = [
        f"## Backend comparison: {scenarios} — {'✅ PASS' if doc['passed'] else '❌ FAIL'}",
        "",
        f"{s['ok']}/{s['runs']} runs pass. Reference: **{doc['reference']}**{limit}. "
        "Cells: status, assertions passed, max position error from the reference.",
        "",
        "| variant | " + " | ".join(backends) + " |",
        "|---|" + "---|" * len(backends),
    ]
    failures: list[str] = []
    for case in doc["cases"]:
        runs = {r["backend"]: r for r in case["runs"]}
        cells = []
        for b in backends:
            r = runs.get(b)
            if r is None:
                cells.append("–")
                continue
            mark = "✅" if r["ok"] else "❌"
            a = r["assertions"]
            text = f"{mark} {r['label']} {a['passed']}/{a['total']}"
            div = case["divergence"].get(b)
            if div and div.get("available"):
                text += f", {_num(div['max']['position'])} m"
            if r["within_max_divergence"] is False:
                text += " (diverged)"
            cells.append(_cell(text))
            for name in case["verdicts"]["assertions"]:
                v = case["verdicts"]["cells"][name].get(b)
                if v is not None and v["passed"] is not True:
                    failures.append(
                        f"- `{case['variant']}` · {b}: **{name}** measured {v['measured']}, expected {v['expected']}"
                    )
            if r["outcome"] is not None or r["status"] not in ("passed", "failed"):
                detail = f": {r['detail'][:200]}" if r["detail"] else ""
                failures.append(f"- `{case['variant']}` · {b}: {r['label']}{_cell(detail)}")
        out.append(f"| {_cell(case['variant'])} | " + " | ".join(cells) + " |")
    if failures:
        out += ["", "### Problems", ""]
        out += failures[:MAX_FAILURES]
        if len(failures) > MAX_FAILURES:
            out.append(f"- … and {len(failures) - MAX_FAILURES} more (see report.html)")
    out += ["", "### Cost (sum over cases)", "", "| backend | engine | wall time (s) | steps/s | real-time factor |",
            "|---|---|---|---|---|"]  # fmt: skip
    for b in backends:
        of_b = [r for c in doc["cases"] for r in c["runs"] if r["backend"] == b]
        walls = [r["cost"]["wall_seconds"] for r in of_b]
        known = [r for r, w in zip(of_b, walls, strict=True) if w]
        wall = sum(r["cost"]["wall_seconds"] for r in known) if known else None
        steps = sum(r["cost"]["steps"] for r in known)
        sim = sum(r["cost"]["simulated_seconds"] or 0.0 for r in known)
        version = of_b[0]["engine_version"] if of_b else ""
        sps = steps / wall if wall else None
        rtf = sim / wall if wall else None
        out.append(f"| {b} | {_cell(version)} | {_num(wall)} | {_num(sps)} | {_num(rtf)} |")
    out += ["", "Full report with plots, pictures, animation and sounds: `report.html`; data: `report.json`.", ""]
    return "\n".join(out)
