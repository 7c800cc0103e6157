"""The side-by-side animation of one case: every run's scene, frame by frame, in one GIF.

Frames are sampled every ``1 / fps`` s of simulated time (at the nearest recorded step, up to each run's
last step; a run that stopped early stays on its last picture). Faces from :mod:`reports.pictures` are
rasterised with numpy (convex polygons by edge tests, discs by distance) into palette indices; the
palette is the exact set of shaded colours when it fits in 255 entries, else a 6x6x6 colour cube.
Frames play in simulated real time. Planes never move, so each panel's floor is drawn once; after the
first frame the encoder stores only the rectangle that changed (:mod:`reports.gif`), so nothing that
changes every frame away from the bodies (a clock, a progress bar) is drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from reports.gif import encode_gif
from reports.pictures import Face, View, scene_faces

__all__ = ["animate"]

_PANEL_BG = (244, 246, 248)
_GAP = (200, 204, 210)


def _fill_polygon(img: np.ndarray, pts: np.ndarray, value: int) -> None:
    h, w = img.shape
    x0, y0 = np.floor(pts.min(axis=0)).astype(int)
    x1, y1 = np.ceil(pts.max(axis=0)).astype(int)
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w - 1), min(y1, h - 1)
    if x1 < x0 or y1 < y0:
        return
    ys, xs = np.mgrid[y0 : y1 + 1, x0 : x1 + 1]
    cx, cy = xs + 0.5, ys + 0.5
    area = np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
    if abs(area) < 1e-9:
        return
    sign = 1.0 if area > 0 else -1.0
    inside = np.ones(cx.shape, dtype=bool)
    for (ax, ay), (bx, by) in zip(pts, np.roll(pts, -1, axis=0), strict=True):
        inside &= sign * ((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)) >= 0
    img[y0 : y1 + 1, x0 : x1 + 1][inside] = value


def _fill_disc(img: np.ndarray, cx: float, cy: float, r: float, value: int) -> None:
    h, w = img.shape
    x0, x1 = max(int(cx - r), 0), min(int(cx + r) + 1, w - 1)
    y0, y1 = max(int(cy - r), 0), min(int(cy + r) + 1, h - 1)
    if x1 < x0 or y1 < y0:
        return
    ys, xs = np.mgrid[y0 : y1 + 1, x0 : x1 + 1]
    inside = (xs + 0.5 - cx) ** 2 + (ys + 0.5 - cy) ** 2 <= r * r
    img[y0 : y1 + 1, x0 : x1 + 1][inside] = value


class _Palette:
    def __init__(self) -> None:
        self.colors: list[tuple[int, int, int]] = []
        self.index: dict[tuple[int, int, int], int] = {}

    def __call__(self, rgb: tuple[int, int, int]) -> int:
        k = self.index.get(rgb)
        if k is None:
            k = self.index[rgb] = len(self.colors)
            self.colors.append(rgb)
        return k


def _render(faces: Sequence[Face], view: View, w: int, h: int, palette: _Palette, base: np.ndarray) -> np.ndarray:
    img = base.copy()
    scale = view.scale(w, h)
    for f in faces:
        px = view.to_pixels(f.points, w, h)
        if f.radius > 0:
            _fill_disc(img, float(px[0, 0]), float(px[0, 1]), f.radius * scale, palette(f.rgb))
        else:
            _fill_polygon(img, px, palette(f.rgb))
    return img


def animate(
    panels: Sequence[tuple[Sequence[dict[str, Any]], np.ndarray, np.ndarray, np.ndarray]],
    view: View,
    *,
    panel_width: int = 260,
    fps: float = 10.0,
    max_frames: int = 150,
) -> bytes:
    """A GIF of ``panels`` side by side: (specs, times (S,), pos (S, N, 3), quat (S, N, 4)) each."""
    if not panels:
        raise ValueError("nothing to animate")
    w, h = view.size(panel_width)
    end = max(float(times[-1]) for _, times, _, _ in panels if len(times))
    count = min(max_frames, int(np.floor(end * fps + 1e-9)) + 1)
    frame_times = np.linspace(0.0, end, count) if count > 1 else np.zeros(1)
    palette = _Palette()
    gap, panel_bg = palette(_GAP), palette(_PANEL_BG)
    full_w = len(panels) * w + (len(panels) - 1) * 2
    floors = []
    for specs, times, pos, quat in panels:
        base = np.full((h, w), panel_bg, dtype=np.int32)
        if len(times):
            faces = scene_faces(specs, pos[0], quat[0], view.centre, view.extent)
            base = _render([f for f in faces if f.floor], view, w, h, palette, base)
        floors.append(base)
    frames = []
    for t in frame_times:
        frame = np.full((h, full_w), gap, dtype=np.int32)
        for k, (specs, times, pos, quat) in enumerate(panels):
            x = k * (w + 2)
            if not len(times):
                frame[:, x : x + w] = floors[k]
                continue
            i = int(np.clip(np.searchsorted(times, t - 1e-9), 0, len(times) - 1))
            faces = [f for f in scene_faces(specs, pos[i], quat[i], view.centre, view.extent) if not f.floor]
            frame[:, x : x + w] = _render(faces, view, w, h, palette, floors[k])
        frames.append(frame)
    colors = palette.colors
    if len(colors) > 255:
        cube = np.array([[r, g, b] for r in range(6) for g in range(6) for b in range(6)]) * 51
        lut = np.array([int(np.argmin(((cube - np.array(c)) ** 2).sum(axis=1))) for c in colors])
        frames = [lut[f] for f in frames]
        colors = [(int(c[0]), int(c[1]), int(c[2])) for c in cube]
    delay = max(2, int(round(100.0 * (end / max(count - 1, 1)) if count > 1 else 100)))
    return encode_gif([f.astype(np.uint8) for f in frames], colors, delay)
