"""The figures of a case in the HTML report: charts (from the document), pictures, animation, audio (from
the traces). Each function returns an HTML fragment; images and sounds are inline (SVG, data: URIs)."""

from __future__ import annotations

import base64
from collections.abc import Sequence
from html import escape
from typing import Any

import numpy as np

from reports.animation import animate
from reports.audio import trace_audio
from reports.pictures import body_specs, fit_view, scene_faces, svg_picture
from reports.plots import Series, color_for, line_chart, timeline_chart
from reports.runs import Run

__all__ = ["animation_html", "divergence_charts", "event_timeline", "pictures_html", "sound_section",
           "trajectory_charts"]  # fmt: skip

PICTURE_WIDTH = 230
PANEL_WIDTH = 240


def _colors(doc: dict[str, Any]) -> dict[str, str]:
    return {b: color_for(i) for i, b in enumerate(doc["backends"])}


def trajectory_charts(doc: dict[str, Any], case: dict[str, Any]) -> str:
    colors = _colors(doc)
    trajectories = {b: t for b, t in case["trajectories"].items() if t}
    bodies: list[str] = []
    for t in trajectories.values():
        bodies += [b for b in t["bodies"] if b not in bodies]
    out = []
    for body in bodies:
        for axis in ("x", "y", "z"):
            series = [
                Series(b, colors[b], t["t"], t["bodies"][body][axis], dashed=b == case["reference"])
                for b, t in trajectories.items()
                if body in t["bodies"]
            ]
            out.append(line_chart(f"{body}.pos.{axis}", series, y_label="m", width=360, height=220))
    return "".join(out) or "<p>No moving bodies.</p>"


def divergence_charts(doc: dict[str, Any], case: dict[str, Any]) -> str:
    colors = _colors(doc)
    th = doc["thresholds"]
    available = {b: d for b, d in case["divergence"].items() if d.get("available")}
    if not available:
        return ""
    bodies: list[str] = []
    joints: list[str] = []
    for d in available.values():
        bodies += [b for b in d["series"]["bodies"] if b not in bodies]
        joints += [j for j in d["series"]["joints"] if j not in joints]
    out = []
    for body in bodies:
        for key, unit, limit in (("position", "m", th["position"]), ("angle", "rad", th["angle"])):
            series = [
                Series(b, colors[b], d["series"]["t"], d["series"]["bodies"][body][key])
                for b, d in available.items()
                if body in d["series"]["bodies"]
            ]
            title = f"{body}: {key} error from {case['reference']}"
            out.append(line_chart(title, series, y_label=unit, width=360, height=220,
                                  hlines=[(limit, f"threshold {limit:g}")]))  # fmt: skip
    for joint in joints:
        series = [
            Series(b, colors[b], d["series"]["joints"][joint]["t"], d["series"]["joints"][joint]["error"])
            for b, d in available.items()
            if joint in d["series"]["joints"]
        ]
        title = f"{joint}: position error from {case['reference']}"
        out.append(line_chart(title, series, y_label="m or rad", width=360, height=220,
                              hlines=[(th["joint"], f"threshold {th['joint']:g}")]))  # fmt: skip
    return "".join(out)


def _end(case: dict[str, Any]) -> float:
    ends = [r["end_time"] for r in case["runs"] if r["end_time"] is not None]
    return max(ends + [case["duration"] or 0.0])


def event_timeline(doc: dict[str, Any], case: dict[str, Any]) -> str:
    colors = _colors(doc)
    ev = case["events"]
    rows = [(b, colors[b], [(e["t"], e["name"]) for e in items]) for b, items in ev["timelines"].items()]
    return timeline_chart("events", rows, ev["names"], _end(case))


def sound_section(doc: dict[str, Any], case: dict[str, Any], runs: dict[str, Run]) -> str:
    colors = _colors(doc)
    sounds = case["sounds"]
    names = list(dict.fromkeys(s["name"] for items in sounds.values() for s in items if s["action"] == "start"))
    if not names:
        return "<p>This case plays no sounds.</p>"
    rows = [
        (b, colors[b], [(s["t"], s["name"]) for s in items if s["action"] == "start"]) for b, items in sounds.items()
    ]
    out = [timeline_chart("sound starts", rows, names, _end(case))]
    out.append('<div class="audio">')
    for backend, run in runs.items():
        wav = trace_audio(run.trace) if run.trace is not None else None
        if wav is None:
            out.append(f"<p><b>{escape(backend)}</b>: no sound played</p>")
            continue
        data = base64.b64encode(wav).decode()
        out.append(f'<figure><figcaption>{escape(backend)}</figcaption><audio controls preload="metadata" '
                   f'src="data:audio/wav;base64,{data}"></audio></figure>')  # fmt: skip
    out.append("</div>")
    return "".join(out)


def _arrays(run: Run) -> tuple[list[dict[str, Any]], np.ndarray, np.ndarray, np.ndarray] | None:
    if run.trace is None or not run.trace.times.size:
        return None
    specs = body_specs(run.trace)
    if not specs:
        return None
    pos = np.stack([run.trace.bodies[s["name"]].pos for s in specs], axis=1)
    quat = np.stack([run.trace.bodies[s["name"]].quat for s in specs], axis=1)
    return specs, run.trace.times, pos, quat


def _view(arrays: Sequence[tuple[Any, np.ndarray, np.ndarray, np.ndarray]]):  # noqa: ANN202 - a View
    samples = []
    for specs, times, pos, quat in arrays:
        stride = max(1, len(times) // 200)
        samples.append((specs, pos[::stride], quat[::stride]))
        samples.append((specs, pos[-1:], quat[-1:]))
    return fit_view(samples)


def pictures_html(case: dict[str, Any], runs: dict[str, Run]) -> str:
    arrays = {b: a for b, r in runs.items() if (a := _arrays(r)) is not None}
    if not arrays:
        return "<p>No recorded steps to draw.</p>"
    view = _view(list(arrays.values()))
    out = ['<table class="pictures"><tr><th>backend</th><th>start</th><th>first event</th><th>end</th></tr>']
    for backend in runs:
        out.append(f"<tr><th>{escape(backend)}</th>")
        moments = case["key_moments"].get(backend) or []
        if backend not in arrays or not moments:
            out.append('<td colspan="3">no recorded steps</td></tr>')
            continue
        specs, times, pos, quat = arrays[backend]
        by_kind = {"start": moments[0], "end": moments[-1]}
        first = [m for m in moments if m["label"].startswith("first event")]
        cells = [by_kind["start"], first[0] if first else None, by_kind["end"]]
        for m in cells:
            if m is None:
                out.append('<td class="none">no event</td>')
                continue
            i = int(np.clip(np.searchsorted(times, m["t"] - 1e-9), 0, len(times) - 1))
            faces = scene_faces(specs, pos[i], quat[i], view.centre, view.extent)
            caption = f"{backend} · {m['label']} · t = {m['t']:g} s"
            label = f"t = {m['t']:g} s" + (f" · {m['label'][len('first event: '):]}" if m is cells[1] else "")
            out.append(f"<td>{svg_picture(faces, view, PICTURE_WIDTH, caption, label)}</td>")
        out.append("</tr>")
    out.append("</table>")
    return "".join(out)


def animation_html(case: dict[str, Any], runs: dict[str, Run]) -> str:
    arrays = {b: a for b, r in runs.items() if (a := _arrays(r)) is not None}
    if not arrays:
        return ""
    view = _view(list(arrays.values()))
    panels = [arrays[b] for b in runs if b in arrays]
    gif = animate(panels, view, panel_width=PANEL_WIDTH)
    w, _ = view.size(PANEL_WIDTH)
    labels = "".join(f'<span style="width:{w + 2}px">{escape(b)}</span>' for b in runs if b in arrays)
    data = base64.b64encode(gif).decode()
    title = f"{case['scenario']} · {case['variant']}: every backend side by side"
    return (f'<div class="animation"><div class="labels">{labels}</div>'
            f'<img class="animation" alt="{escape(title)}" title="{escape(title)}" '
            f'src="data:image/gif;base64,{data}"></div>')  # fmt: skip
