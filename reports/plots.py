"""Small self-contained SVG charts (no plotting library): line charts and event timelines.

Every chart is one ``<svg class="plot">`` element with a ``<title>``, sized in pixels, with axes, nice
ticks, a legend, and one polyline per series (broken where a value is missing). Text is escaped. The
output depends only on the data, so a report rebuilt from the same traces draws the same bytes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from html import escape

__all__ = ["PALETTE", "Series", "color_for", "line_chart", "nice_ticks", "timeline_chart"]

#: colour per backend, in report order (the reference first)
PALETTE = ("#1f4e9c", "#d1495b", "#2e9e5b", "#e08a1e", "#7b4fa3", "#7a5230", "#2a9fb0", "#b5468b")
_FONT = 'font-family="system-ui, sans-serif"'
_MARGIN = (56, 16, 44, 38)  # left, right, top (title + legend), bottom


def color_for(index: int) -> str:
    return PALETTE[index % len(PALETTE)]


@dataclass(frozen=True)
class Series:
    label: str
    color: str
    x: Sequence[float]
    y: Sequence[float | None]
    dashed: bool = False


def nice_ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """About ``count`` round tick values covering [lo, hi]."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return []
    if hi <= lo:
        return [lo]
    raw = (hi - lo) / max(count, 1)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw)
    first = math.ceil(lo / step - 1e-9) * step
    ticks = []
    k = 0
    while first + k * step <= hi + step * 1e-9:
        ticks.append(round(first + k * step, 12))
        k += 1
    return ticks


def _fmt(v: float) -> str:
    if v == 0:
        return "0"
    if abs(v) >= 1e4 or abs(v) < 1e-3:
        return f"{v:.2g}"
    return f"{v:.6g}"


def _range(values: Sequence[float]) -> tuple[float, float]:
    lo, hi = min(values), max(values)
    if hi - lo < 1e-12:
        pad = max(abs(lo) * 0.05, 1e-6)
        return lo - pad, hi + pad
    pad = (hi - lo) * 0.05
    return lo - pad, hi + pad


def _legend(items: Sequence[tuple[str, str, bool]], x0: float, y: float, width: float) -> list[str]:
    out, x = [], x0
    for label, color, dashed in items:
        w = 26 + 6.5 * len(label)
        if x + w > x0 + width and x > x0:
            break
        dash = ' stroke-dasharray="5 3"' if dashed else ""
        out.append(f'<line x1="{x:.1f}" y1="{y - 4:.1f}" x2="{x + 18:.1f}" y2="{y - 4:.1f}" stroke="{color}" '
                   f'stroke-width="2.5"{dash}/>')  # fmt: skip
        out.append(f'<text x="{x + 22:.1f}" y="{y:.1f}" font-size="11" {_FONT}>{escape(label)}</text>')
        x += w
    return out


def _frame(title: str, width: int, height: int) -> list[str]:
    return [
        f'<svg class="plot" xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}" role="img">',
        f"<title>{escape(title)}</title>",
        f'<rect width="{width}" height="{height}" fill="#ffffff"/>',
        f'<text x="{_MARGIN[0]}" y="15" font-size="13" font-weight="600" {_FONT}>{escape(title)}</text>',
    ]


def line_chart(
    title: str,
    series: Sequence[Series],
    *,
    x_label: str = "t (s)",
    y_label: str = "",
    width: int = 520,
    height: int = 250,
    hlines: Sequence[tuple[float, str]] = (),
) -> str:
    """A line chart of ``series``; ``hlines`` are labelled horizontal reference lines (thresholds)."""
    left, right, top, bottom = _MARGIN
    pw, ph = width - left - right, height - top - bottom
    xs = [float(x) for s in series for x in s.x]
    ys = [float(y) for s in series for y in s.y if y is not None and math.isfinite(y)]
    ys += [v for v, _ in hlines]
    out = _frame(title, width, height)
    out += _legend([(s.label, s.color, s.dashed) for s in series], left, 31, pw)
    if not xs or not ys:
        out.append(f'<text x="{left + pw / 2}" y="{top + ph / 2}" text-anchor="middle" font-size="12" {_FONT}>'
                   "no data</text></svg>")  # fmt: skip
        return "".join(out)
    x0, x1 = min(xs), max(xs)
    if x1 <= x0:
        x1 = x0 + 1.0
    y0, y1 = _range(ys)

    def px(x: float) -> float:
        return left + (x - x0) / (x1 - x0) * pw

    def py(y: float) -> float:
        return top + ph - (y - y0) / (y1 - y0) * ph

    out.append(f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="#fafafa" stroke="#bbbbbb"/>')
    for t in nice_ticks(y0, y1):
        if y0 <= t <= y1:
            y = py(t)
            out.append(f'<line x1="{left}" y1="{y:.1f}" x2="{left + pw}" y2="{y:.1f}" stroke="#e4e4e4"/>')
            out.append(f'<text x="{left - 4}" y="{y + 3.5:.1f}" text-anchor="end" font-size="10" {_FONT}>'
                       f"{_fmt(t)}</text>")  # fmt: skip
    for t in nice_ticks(x0, x1, 8):
        if x0 <= t <= x1:
            x = px(t)
            out.append(f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{top + ph}" stroke="#eeeeee"/>')
            out.append(f'<text x="{x:.1f}" y="{top + ph + 13}" text-anchor="middle" font-size="10" {_FONT}>'
                       f"{_fmt(t)}</text>")  # fmt: skip
    out.append(f'<text x="{left + pw / 2}" y="{height - 6}" text-anchor="middle" font-size="11" {_FONT}>'
               f"{escape(x_label)}</text>")  # fmt: skip
    if y_label:
        out.append(f'<text transform="translate(13 {top + ph / 2}) rotate(-90)" text-anchor="middle" '
                   f'font-size="11" {_FONT}>{escape(y_label)}</text>')  # fmt: skip
    for value, label in hlines:
        y = py(value)
        out.append(f'<line x1="{left}" y1="{y:.1f}" x2="{left + pw}" y2="{y:.1f}" stroke="#888888" '
                   'stroke-dasharray="2 3"/>')  # fmt: skip
        out.append(f'<text x="{left + pw - 3}" y="{y - 3:.1f}" text-anchor="end" font-size="10" fill="#666666" '
                   f"{_FONT}>{escape(label)}</text>")  # fmt: skip
    for s in sorted(series, key=lambda s: s.dashed):  # dashed (the reference) last, on top
        dash = ' stroke-dasharray="6 3"' if s.dashed else ""
        for run in _segments(s.x, s.y):
            points = " ".join(f"{px(x):.2f},{py(y):.2f}" for x, y in run)
            if len(run) == 1:
                x, y = run[0]
                out.append(f'<circle cx="{px(x):.2f}" cy="{py(y):.2f}" r="2" fill="{s.color}"/>')
            else:
                out.append(f'<polyline fill="none" stroke="{s.color}" stroke-width="1.6"{dash} '
                           f'stroke-linejoin="round" points="{points}"/>')  # fmt: skip
    out.append("</svg>")
    return "".join(out)


def _segments(xs: Sequence[float], ys: Sequence[float | None]) -> list[list[tuple[float, float]]]:
    runs: list[list[tuple[float, float]]] = [[]]
    for x, y in zip(xs, ys, strict=False):
        if y is None or not math.isfinite(y):
            if runs[-1]:
                runs.append([])
            continue
        runs[-1].append((float(x), float(y)))
    return [r for r in runs if r]


def timeline_chart(
    title: str,
    rows: Sequence[tuple[str, str, Sequence[tuple[float, str]]]],
    names: Sequence[str],
    t_end: float,
    *,
    width: int = 760,
    markers: Sequence[str] = ("circle", "square", "diamond", "triangle"),
) -> str:
    """One row per run (label, colour, [(t, event name)]): a marker per occurrence, shaped by event name."""
    left, right = 110, 16
    row_h, top = 26, 44
    height = top + row_h * max(len(rows), 1) + 34
    pw = width - left - right
    t1 = t_end if t_end > 0 else 1.0
    out = _frame(title, width, height)
    shape = {n: markers[i % len(markers)] for i, n in enumerate(names)}
    legend_x = float(left)
    for n in names:
        out.append(_marker(shape[n], legend_x + 5, 27, "#444444"))
        out.append(f'<text x="{legend_x + 13:.1f}" y="31" font-size="11" {_FONT}>{escape(n)}</text>')
        legend_x += 24 + 6.5 * len(n)
    for t in nice_ticks(0.0, t1, 10):
        x = left + t / t1 * pw
        out.append(f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{height - 30}" stroke="#eeeeee"/>')
        out.append(f'<text x="{x:.1f}" y="{height - 17}" text-anchor="middle" font-size="10" {_FONT}>'
                   f"{_fmt(t)}</text>")  # fmt: skip
    out.append(f'<text x="{left + pw / 2}" y="{height - 4}" text-anchor="middle" font-size="11" {_FONT}>'
               "t (s)</text>")  # fmt: skip
    for i, (label, color, items) in enumerate(rows):
        y = top + row_h * i + row_h / 2
        out.append(f'<line x1="{left}" y1="{y:.1f}" x2="{left + pw}" y2="{y:.1f}" stroke="#d8d8d8"/>')
        out.append(f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end" font-size="11" {_FONT}>'
                   f"{escape(label)}</text>")  # fmt: skip
        for t, name in items:
            x = left + min(max(t, 0.0), t1) / t1 * pw
            out.append(_marker(shape.get(name, "circle"), x, y, color, f"{name} at {t:g} s"))
    out.append("</svg>")
    return "".join(out)


def _marker(kind: str, x: float, y: float, color: str, tip: str = "") -> str:
    title = f"<title>{escape(tip)}</title>" if tip else ""
    if kind == "square":
        body = f'<rect x="{x - 4:.1f}" y="{y - 4:.1f}" width="8" height="8" fill="{color}"'
    elif kind == "diamond":
        body = f'<polygon points="{x:.1f},{y - 5:.1f} {x + 5:.1f},{y:.1f} {x:.1f},{y + 5:.1f} {x - 5:.1f},{y:.1f}" ' \
               f'fill="{color}"'  # fmt: skip
    elif kind == "triangle":
        body = f'<polygon points="{x:.1f},{y - 5:.1f} {x + 5:.1f},{y + 4:.1f} {x - 5:.1f},{y + 4:.1f}" fill="{color}"'
    else:
        body = f'<circle cx="{x:.1f}" cy="{y:.1f}" r="4.5" fill="{color}"'
    return f'{body} fill-opacity="0.85">{title}</{body.split()[0][1:]}>' if title else f"{body} fill-opacity=\"0.85\"/>"
