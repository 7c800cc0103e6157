"""A small SVG plot of the signal where a run first left its golden file (written by hand, no dependency).

A sampled signal is drawn as the golden's curve with its tolerance band, the run's curve, and a dashed line
at the first divergence; an event or sound divergence as two timelines (golden above, run below).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from runner.ci.golden import Tolerances, _num
from runner.ci.golden_compare import Comparison, series

WIDTH, HEIGHT = 720, 320
LEFT, RIGHT, TOP, BOTTOM = 72, 16, 40, 44
GOLDEN, RUN, BAND, MARK = "#1f5fa8", "#c8302c", "#1f5fa8", "#444444"


def write_divergence_plot(comparison: Comparison, tolerances: Tolerances, path: Path) -> Path | None:
    """Plot the first divergence of ``comparison`` into ``path``; None when there is nothing to plot."""
    first = comparison.first
    if first is None:
        return None
    exp, got = comparison.expected, comparison.got
    title = f"{exp.label()}: {first.kind} {first.name} {first.field}"
    if first.kind in ("event", "sound"):
        pick = (lambda r: r.events) if first.kind == "event" else (lambda r: r.sounds)
        svg = timeline_svg(title, pick(exp), pick(got), first.time)
    else:
        e = series(exp, first.kind, first.name, first.field)
        g = series(got, first.kind, first.name, first.field)
        if e is None or g is None:
            return None
        n = min(len(e), len(g))
        fld = "state" if first.kind == "var" else first.field.split(".")[0]
        atol, rtol = tolerances.lookup(first.name, fld)
        if first.field.startswith("quat."):  # the sign the comparison chose
            g = _aligned_quat_component(comparison, first.name, first.field, g)
        svg = signal_svg(title, exp.times[:n], e[:n], g[:n], atol + rtol * np.abs(e[:n]), first.time)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(svg, encoding="utf-8")
    return path


def _aligned_quat_component(comparison: Comparison, body: str, label: str, g: np.ndarray) -> np.ndarray:
    e4 = comparison.expected.bodies[body][:, 3:7]
    g4 = comparison.got.bodies[body][:, 3:7]
    n = min(len(e4), len(g4))
    flip = np.nansum(e4[:n] * g4[:n], axis=1) < 0
    out = np.array(g[:n], float)
    out[flip] = -out[flip]
    return out


def _ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    if not math.isfinite(lo) or not math.isfinite(hi) or hi <= lo:
        return [lo] if math.isfinite(lo) else []
    raw = (hi - lo) / count
    mag = 10 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw)
    start = math.ceil(lo / step) * step
    return [start + i * step for i in range(int((hi - start) / step + 1e-9) + 1)]


class _Frame:
    def __init__(self, t0: float, t1: float, y0: float, y1: float) -> None:
        if t1 <= t0:
            t1 = t0 + 1.0
        if y1 <= y0:
            pad = abs(y0) * 0.05 or 1e-9
            y0, y1 = y0 - pad, y1 + pad
        self.t0, self.t1, self.y0, self.y1 = t0, t1, y0, y1

    def x(self, t: float) -> float:
        return LEFT + (t - self.t0) / (self.t1 - self.t0) * (WIDTH - LEFT - RIGHT)

    def y(self, v: float) -> float:
        return TOP + (self.y1 - v) / (self.y1 - self.y0) * (HEIGHT - TOP - BOTTOM)

    def axes(self, parts: list[str], yticks: bool = True) -> None:
        x0, x1, yb, yt = LEFT, WIDTH - RIGHT, HEIGHT - BOTTOM, TOP
        parts.append(f'<rect x="{x0}" y="{yt}" width="{x1 - x0}" height="{yb - yt}" fill="none" stroke="#999"/>')
        for t in _ticks(self.t0, self.t1):
            x = self.x(t)
            parts.append(f'<line x1="{x:.1f}" y1="{yb}" x2="{x:.1f}" y2="{yb + 4}" stroke="#999"/>')
            parts.append(f'<text x="{x:.1f}" y="{yb + 16}" text-anchor="middle">{_num(round(t, 9))}</text>')
        parts.append(f'<text x="{(x0 + x1) / 2:.1f}" y="{HEIGHT - 8}" text-anchor="middle">time (s)</text>')
        if yticks:
            for v in _ticks(self.y0, self.y1):
                y = self.y(v)
                parts.append(f'<line x1="{x0 - 4}" y1="{y:.1f}" x2="{x0}" y2="{y:.1f}" stroke="#999"/>')
                parts.append(f'<text x="{x0 - 6}" y="{y + 4:.1f}" text-anchor="end">{_num(float(f"{v:.6g}"))}</text>')


def _svg(title: str, body: list[str]) -> str:
    head = (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" '
        f'viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="11">'
    )
    bg = f'<rect width="{WIDTH}" height="{HEIGHT}" fill="white"/>'
    heading = f'<text x="{LEFT}" y="18" font-size="13" font-weight="bold">{escape(title)}</text>'
    return "\n".join([head, bg, heading, *body, "</svg>"]) + "\n"


def _path(frame: _Frame, t: np.ndarray, v: np.ndarray) -> str:
    points, pen = [], "M"
    for ti, vi in zip(t, v, strict=True):
        if not math.isfinite(vi):
            pen = "M"
            continue
        points.append(f"{pen}{frame.x(float(ti)):.1f},{frame.y(float(vi)):.1f}")
        pen = "L"
    return " ".join(points)


def signal_svg(
    title: str, t: np.ndarray, expected: np.ndarray, got: np.ndarray, bound: np.ndarray, first: float
) -> str:
    """The golden curve with its tolerance band, the run's curve, and the first divergence."""
    finite = np.concatenate([expected - bound, expected + bound, got])
    finite = finite[np.isfinite(finite)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    frame = _Frame(float(t[0]) if len(t) else 0.0, float(t[-1]) if len(t) else 1.0, lo, hi)
    parts: list[str] = []
    frame.axes(parts)
    upper = [f"{frame.x(float(a)):.1f},{frame.y(float(b)):.1f}" for a, b in zip(t, expected + bound, strict=True)
             if math.isfinite(b)]  # fmt: skip
    lower = [f"{frame.x(float(a)):.1f},{frame.y(float(b)):.1f}" for a, b in zip(t, expected - bound, strict=True)
             if math.isfinite(b)]  # fmt: skip
    if upper and lower:
        pts = " ".join(upper + lower[::-1])
        parts.append(f'<polygon points="{pts}" fill="{BAND}" fill-opacity="0.15" stroke="none"/>')
    parts.append(f'<path d="{_path(frame, t, expected)}" fill="none" stroke="{GOLDEN}" stroke-width="1.6"/>')
    parts.append(f'<path d="{_path(frame, t, got)}" fill="none" stroke="{RUN}" stroke-width="1.4"/>')
    _first_line(parts, frame, first)
    _legend(parts, [(GOLDEN, "baseline (band: tolerance)"), (RUN, "this run")])
    return _svg(title, parts)


def timeline_svg(
    title: str, expected: Sequence[tuple[float, str, str]], got: Sequence[tuple[float, str, str]], first: float
) -> str:
    """Two rows of event marks, the golden's above the run's, with the first divergence."""
    times = [t for t, _, _ in expected] + [t for t, _, _ in got] + [first]
    frame = _Frame(0.0, max(times) * 1.05 if times else 1.0, 0.0, 3.0)
    parts: list[str] = []
    frame.axes(parts, yticks=False)
    for row, color, label, items in ((2.0, GOLDEN, "baseline", expected), (1.0, RUN, "this run", got)):
        y = frame.y(row)
        parts.append(f'<text x="{LEFT - 6}" y="{y + 4:.1f}" text-anchor="end">{label}</text>')
        for i, (t, name, _src) in enumerate(items):
            x = frame.x(t)
            parts.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="3.5" fill="{color}"/>')
            dy = -8 if i % 2 == 0 else 16
            parts.append(f'<text x="{x:.1f}" y="{y + dy:.1f}" text-anchor="middle" font-size="9">{escape(name)}</text>')
    _first_line(parts, frame, first)
    return _svg(title, parts)


def _first_line(parts: list[str], frame: _Frame, first: float) -> None:
    x = frame.x(first)
    parts.append(
        f'<line x1="{x:.1f}" y1="{TOP}" x2="{x:.1f}" y2="{HEIGHT - BOTTOM}" stroke="{MARK}" stroke-dasharray="4 3"/>'
    )
    label = f"first divergence {_num(first)} s"
    if x > LEFT + 0.7 * (WIDTH - LEFT - RIGHT):  # near the right edge: the label goes to the line's left
        parts.append(f'<text x="{x - 4:.1f}" y="{TOP + 12}" fill="{MARK}" text-anchor="end">{label}</text>')
    else:
        parts.append(f'<text x="{x + 4:.1f}" y="{TOP + 12}" fill="{MARK}">{label}</text>')


def _legend(parts: list[str], items: list[tuple[str, str]]) -> None:
    x = WIDTH - RIGHT - 200
    for i, (color, label) in enumerate(items):
        y = TOP + 14 + 14 * i
        parts.append(f'<line x1="{x}" y1="{y - 4}" x2="{x + 18}" y2="{y - 4}" stroke="{color}" stroke-width="2"/>')
        parts.append(f'<text x="{x + 24}" y="{y}">{escape(label)}</text>')
