"""The words at the top of a report and of each case: assertions, then agreement, said apart.

The badge follows the assertions: PASS when every run finished and every assertion passed, FAIL
otherwise. Agreement is its own statement and turns the badge to FAIL only when the comparison asked
for it (``--require-agreement``, or a run beyond ``--max-divergence``). It says, in this order:

* the engines that miss a known truth (stated by a joint's constraint or an analytic reference), each
  judged on its own: "dart misses the truth by up to 1.2 cm (door off the slider's line) from 1.04 s";
* with ``--reference``, the engines that diverge from that engine's run where no truth is known;
* the engines that depart from a majority where no truth is known (reports.consensus), with the cause
  when the data show one (reports.causes): "ode departs from the other 3 from 1.08 s by up to 3.15 cm
  (box position); its door sits 8.11 mm off the slider's line, ...";
* the engines that meet a truth the majority they depart from misses (the truth wins: they are not named);
* the quantities on which no majority formed, with the groups;
* else "4 engines agree".

The exit code of ``compare`` and ``report`` follows the badge (docs/report-schema.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["amount", "headline", "merge"]


def _plural(n: int, one: str, many: str | None = None) -> str:
    return f"{n} {one if n == 1 else (many or one + 's')}"


def amount(value: float | None, unit: str) -> str:
    """A deviation as a reader takes it in: 3.15 cm, 8.11 mm, 42 µm, 0.0284 rad."""
    if value is None:
        return "–"
    if unit != "m":
        return f"{value:.3g} {unit}"
    for scale, name in ((1.0, "m"), (1e-2, "cm"), (1e-3, "mm"), (1e-6, "µm")):
        if abs(value) >= scale or name == "µm":
            return f"{value / scale:.3g} {name}"
    return f"{value:g} m"  # pragma: no cover


def _ratio(item: dict[str, Any]) -> float:
    return (item["max"] or 0.0) / item["threshold"] if item["threshold"] else 0.0


def _worst(items: list[dict[str, Any]]) -> dict[str, Any]:
    return max(items, key=lambda d: (_ratio(d), -(d["from"] or 0.0)))


def _by_backend(found: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One entry per backend: its worst quantity (by deviation over threshold), the earliest time, a count."""
    out = []
    for backend in dict.fromkeys(d["backend"] for d in found):
        mine = [d for d in found if d["backend"] == backend]
        worst = _worst(mine)
        firsts = [d["from"] for d in mine if d["from"] is not None]
        out.append({**worst, "from": min(firsts) if firsts else None,
                    "quantities": list(dict.fromkeys(d["label"] for d in mine))})
    return out


def headline(runs: Sequence[dict[str, Any]], quantities: Sequence[dict[str, Any]],
             causes: dict[str, Any] | None = None, required: bool = False) -> dict[str, Any]:  # fmt: skip
    """The headline of one case from its runs and quantities (as in the comparison document); ``causes``:
    backend -> what explains its departure (reports.causes); ``required``: agreement decides the badge."""
    failed = sum(r["assertions"]["failed"] for r in runs)
    total = sum(r["assertions"]["total"] for r in runs)
    broken = [r for r in runs if r["status"] not in ("passed", "failed")]
    misses: list[dict[str, Any]] = []
    diverges: list[dict[str, Any]] = []
    departures: list[dict[str, Any]] = []
    overruled: list[dict[str, Any]] = []
    split: list[dict[str, Any]] = []
    for q in quantities:
        common = {"quantity": q["id"], "label": q["label"], "unit": q["unit"], "threshold": q["threshold"]}
        verdict = q.get("agreement")
        if verdict is None:
            found = [{"backend": b, **common, "max": q["deviation"][b]["max"],
                      "from": q["deviation"][b]["first_over"]} for b in q["diverging"]]  # fmt: skip
            if q["truth"]["kind"] == "reference":
                diverges += [{**d, "reference": q["truth"]["backend"]} for d in found]
            else:
                misses += found
            continue
        departures += [{"backend": d["backend"], **common, "majority": d["majority"], "max": d["max"],
                        "from": d["from"]} for d in verdict["departures"] if not d.get("overruled")]  # fmt: skip
        overruled += [{"backend": d["backend"], **common, "majority": d["majority"], "max": d["max"],
                       "from": d["from"]} for d in verdict["departures"] if d.get("overruled")]  # fmt: skip
        if verdict["no_majority_from"] is not None:
            split.append({**common, "from": verdict["no_majority_from"], "groups": verdict["groups"]})
    leaving = _by_backend(departures)
    for d in leaving:
        d["cause"] = (causes or {}).get(d["backend"])
    firsts = [d["from"] for d in misses + diverges + departures + split if d["from"] is not None]
    return _words({
        "assertions": {"passed": failed == 0 and not broken, "failed": failed, "total": total,
                       "runs_not_finished": len(broken), "not_finished": [r["label"] for r in broken]},
        "agreement": {"agrees": not (misses or diverges or departures or split), "required": required,
                      "engines": sum(r.get("end_time") is not None for r in runs), "quantities": len(quantities),
                      "truths": sum(q["truth"]["kind"] in ("constraint", "analytic") for q in quantities),
                      "diverging": sum(bool(q["diverging"]) or bool(q.get("agreement", {}).get("no_majority_from")
                                                                      is not None) for q in quantities),
                      "first_over": min(firsts) if firsts else None,
                      "backends": sorted({d["backend"] for d in misses + diverges + departures}),
                      "misses": _by_backend(misses), "diverges": _by_backend(diverges), "departures": leaving,
                      "no_majority": split,
                      "truth_wins": _by_backend(overruled)},
        "within_max_divergence": all(r.get("within_max_divergence") is not False for r in runs),
    })  # fmt: skip


def merge(parts: Sequence[dict[str, Any]], names: Sequence[str] = ()) -> dict[str, Any]:
    """The overall headline from the cases' headlines (``names``: the cases' variants, for the words)."""
    a = [p["assertions"] for p in parts]
    g = [p["agreement"] for p in parts]
    names = list(names) or [str(i) for i in range(len(parts))]
    firsts = [x["first_over"] for x in g if x["first_over"] is not None]

    def across(key: str) -> list[dict[str, Any]]:
        found = []
        for backend in dict.fromkeys(d["backend"] for x in g for d in x[key]):
            mine = [d for x in g for d in x[key] if d["backend"] == backend]
            worst = _worst(mine)
            starts = [d["from"] for d in mine if d["from"] is not None]
            cause = worst.get("cause") or next((d["cause"] for d in mine if d.get("cause")), None)
            found.append({**worst, "from": min(starts) if starts else None, "cases": len(mine),
                          "quantities": list(dict.fromkeys(label for d in mine for label in d["quantities"])),
                          **({"cause": cause} if key == "departures" else {})})  # fmt: skip
        return found

    return _words({
        "cases": len(parts),
        "assertions": {"passed": all(x["passed"] for x in a), "failed": sum(x["failed"] for x in a),
                       "total": sum(x["total"] for x in a), "runs_not_finished": sum(x["runs_not_finished"] for x in a),
                       "not_finished": [label for x in a for label in x["not_finished"]]},
        "agreement": {"agrees": all(x["agrees"] for x in g), "required": any(x["required"] for x in g),
                      "engines": max([x["engines"] for x in g] + [0]), "quantities": sum(x["quantities"] for x in g),
                      "truths": sum(x["truths"] for x in g),
                      "diverging": sum(x["diverging"] for x in g), "first_over": min(firsts) if firsts else None,
                      "cases_diverging": sum(not x["agrees"] for x in g),
                      "backends": sorted({b for x in g for b in x["backends"]}),
                      "misses": across("misses"), "diverges": across("diverges"), "departures": across("departures"),
                      "truth_wins": across("truth_wins"),
                      "no_majority": [{**s, "case": n}
                                      for n, x in zip(names, g, strict=True) for s in x["no_majority"]]},
        "within_max_divergence": all(p["within_max_divergence"] for p in parts),
    })  # fmt: skip


def _in_cases(d: dict[str, Any], cases: int) -> str:
    return f" in {d['cases']} of {cases} cases" if cases > 1 else ""


def _more(d: dict[str, Any]) -> str:
    n = len(d["quantities"])
    return f" and {_plural(n - 1, 'more quantity', 'more quantities')}" if n > 1 else ""


def _cause(c: dict[str, Any] | None) -> str:
    if not c:
        return ""
    where = c["label"][len(c["body"]) + 1 :] if c["label"].startswith(c["body"] + " ") else c["label"]
    return (f"; its {c['body']} sits {amount(c['measured'], 'm')} {where}, the sag ERP {c['erp']:g} and CFM "
            f"{c['cfm']:g} predict for its {c['load']:.4g} N load ({amount(c['predicted'], 'm')} ± "
            f"{c['margin']:.0%})")  # fmt: skip


def _agreement_words(g: dict[str, Any], cases: int) -> list[str]:
    said = []
    for d in g["misses"]:
        when = f" from {d['from']:g} s" if d["from"] is not None else ""
        said.append(f"{d['backend']} misses the truth{_in_cases(d, cases)} by up to {amount(d['max'], d['unit'])} "
                    f"({d['label']}{_more(d)}){when}")  # fmt: skip
    for d in g["diverges"]:
        when = f" from {d['from']:g} s" if d["from"] is not None else ""
        said.append(f"{d['backend']} diverges from {d['reference']}'s run{_in_cases(d, cases)} by up to "
                    f"{amount(d['max'], d['unit'])} ({d['label']}{_more(d)}){when}")  # fmt: skip
    for d in g["departures"]:
        others = (f"the other {len(d['majority'])}" if len(d["majority"]) == g["engines"] - 1
                  else f"the majority ({', '.join(d['majority'])})")  # fmt: skip
        when = f" from {d['from']:g} s" if d["from"] is not None else ""
        said.append(f"{d['backend']} departs from {others}{_in_cases(d, cases)}{when} by up to "
                    f"{amount(d['max'], d['unit'])} ({d['label']}{_more(d)}){_cause(d.get('cause'))}")  # fmt: skip
    for d in g["truth_wins"]:
        said.append(f"{d['backend']} meets the truth that {', '.join(d['majority'])} miss{_in_cases(d, cases)} "
                    f"(it departs from them on {d['label']}{_more(d)})")  # fmt: skip
    split = g["no_majority"]
    if split:
        s = split[0]
        where = f"{s['case']}: " if cases > 1 else ""
        groups = " | ".join(", ".join(group) for group in s["groups"])
        extra = f"; {len(split) - 1} more" if len(split) > 1 else ""
        said.append(f"no majority{_in_cases({'cases': len({x.get('case') for x in split})}, cases)} "
                    f"({where}{s['label']} from {s['from']:g} s: {groups}{extra})")  # fmt: skip
    if said:
        return said
    if not g["quantities"]:
        return ["no quantity compared"]
    if g["engines"] >= 2:
        return [f"{g['engines']} engines agree"]
    return ["within the truth" if g["truths"] else "1 engine: nothing to compare it with"]


def _words(h: dict[str, Any]) -> dict[str, Any]:
    a, g = h["assertions"], h["agreement"]
    said = []
    if a["failed"]:
        said.append(f"{_plural(a['failed'], 'assertion')} fail" + ("s" if a["failed"] == 1 else ""))
    if a["runs_not_finished"]:
        kinds = sorted(set(a["not_finished"]))
        said.append(f"{_plural(a['runs_not_finished'], 'run')} {' / '.join(kinds)}")
    if not said:
        said.append("assertions pass")
    said += _agreement_words(g, h.get("cases", 1))
    if not h["within_max_divergence"]:
        said.append("beyond --max-divergence")
    elif g["required"] and not g["agrees"]:
        said.append("agreement required")
    ok = a["passed"] and h["within_max_divergence"] and (g["agrees"] or not g["required"])
    return {**h, "badge": "PASS" if ok else "FAIL", "text": " · ".join(said)}
