"""The moments of a case worth a picture: the start, each asserted time (or a window's failure) that
failed or came close, the first divergence, the end. One list per case, so every backend is pictured at
the same times and the pictures compare at a glance.

"Close" means a stated value used more than :data:`CLOSE` of its tolerance. Moments closer together than
one recorded step are merged (their reasons joined); at most :data:`LIMIT` are kept, failures first.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["CLOSE", "LIMIT", "key_moments"]

CLOSE = 0.75
LIMIT = 6


def _r(x: float) -> float:
    return round(float(x), 9)


def key_moments(case: dict[str, Any], end: float, dt: float) -> list[dict[str, Any]]:
    """[{"t", "label", "reasons": [...]}] in time order, from a case of the comparison document."""
    found: list[tuple[int, float, str]] = [(0, 0.0, "start")]
    for name in case["verdicts"]["assertions"]:
        failing: dict[float, list[str]] = {}
        for backend, cell in case["verdicts"]["cells"][name].items():
            if cell is not None and cell.get("time") is not None and cell["passed"] is not True:
                failing.setdefault(float(cell["time"]), []).append(backend)
        found += [(1, t, f"{name} fails ({', '.join(who)})") for t, who in failing.items()]
    for row in case["stated"]:
        close: dict[float, list[str]] = {}
        for backend, cell in row["cells"].items():
            tol, dev = cell["tolerance"], cell["deviation"]
            if cell["passed"] and tol and cell["time"] is not None and abs(dev) > CLOSE * tol:
                close.setdefault(float(cell["time"]), []).append(backend)
        found += [(2, t, f"{row['name']} close to its tolerance ({', '.join(who)})") for t, who in close.items()]
    firsts = [(q["first_over"], q) for q in case["quantities"] if q["first_over"] is not None]
    if firsts:
        t, q = min(firsts, key=lambda item: item[0])
        departed = {d["backend"]: d["from"] for d in q.get("agreement", {}).get("departures", [])}
        who = ", ".join(b for b in q["diverging"] if departed.get(b, q["deviation"].get(b, {}).get("first_over")) == t)
        found.append((1, float(t), f"first divergence: {q['label']} ({who})"))
    found.append((0, float(end), "end"))
    merged: list[dict[str, Any]] = []
    for rank, t, reason in sorted(found, key=lambda item: (item[1], item[0])):
        if merged and abs(merged[-1]["t"] - t) < max(dt, 1e-9) / 2 + 1e-9:
            if reason not in merged[-1]["reasons"]:
                merged[-1]["reasons"].append(reason)
                merged[-1]["rank"] = min(merged[-1]["rank"], rank)
            continue
        merged.append({"t": _r(t), "reasons": [reason], "rank": rank})
    if len(merged) > LIMIT:
        keep = sorted(merged, key=lambda m: (m["rank"] if 0 < m["t"] < end else -1, m["t"]))[:LIMIT]
        merged = sorted(keep, key=lambda m: m["t"])
    return [{"t": m["t"], "label": _label(m["reasons"]), "reasons": m["reasons"]} for m in merged]


def _label(reasons: Sequence[str]) -> str:
    head = reasons[0]
    return head if len(reasons) == 1 else f"{head} (+{len(reasons) - 1})"
