"""The scene drawn from a trace: every body's shape (trace metadata) at its recorded pose, as SVG.

A fixed oblique orthographic camera (from the front-right, above; world z up) projects flat-shaded
faces, drawn back to front (painter's algorithm, back faces culled; planes first, as the floor). One
:class:`View` is fitted to every run of a case, so pictures of different backends share one scale and
can be compared side by side. Shapes follow backends.types: boxes by full edge lengths; cylinders and
capsules along local z; a plane through its body's origin with normal local +z, drawn as a square
around the scene. Visual scale changes made by intervals after the start are not drawn.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from html import escape
from typing import Any

import numpy as np

from reports import trace_format as tf
from reports.trace_reader import Trace

__all__ = ["Face", "View", "body_specs", "fit_view", "scene_faces", "svg_picture"]

_CAMERA = np.array([0.45, -1.0, 0.55]) / np.linalg.norm([0.45, -1.0, 0.55])  # towards the viewer
_LIGHT = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
_SIDES = 16  # facets of a cylinder
SHADES = 8  # shading levels (the GIF palette needs few colours)


@dataclass(frozen=True)
class Face:
    depth: float  # larger is nearer the viewer
    points: np.ndarray  # (k, 2) view coordinates (metres), convex, or the centre of a disc
    rgb: tuple[int, int, int]
    radius: float = 0.0  # > 0: a disc (a sphere's outline) of this radius around points[0]
    floor: bool = False  # planes: drawn before everything else


def body_specs(trace: Trace) -> list[dict[str, Any]]:
    specs = json.loads(trace.scenario.get(tf.KEY_BODY_SPECS, "[]"))
    return [s for s in specs if isinstance(s, dict) and s.get("name") in trace.bodies]


def _basis() -> tuple[np.ndarray, np.ndarray]:
    forward = -_CAMERA
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return right, up


_RIGHT, _UP = _basis()


def _rot(q: Sequence[float]) -> np.ndarray:
    w, x, y, z = (float(c) for c in q)
    n = math.sqrt(w * w + x * x + y * y + z * z) or 1.0
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _box(size: Sequence[float]) -> list[tuple[np.ndarray, np.ndarray]]:
    hx, hy, hz = (float(s) / 2 for s in size)
    out = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            normal = np.zeros(3)
            normal[axis] = sign
            a, b = [k for k in range(3) if k != axis]
            half = np.array([hx, hy, hz])
            corners = []
            for da, db in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = np.zeros(3)
                p[axis] = sign * half[axis]
                p[a], p[b] = da * half[a], db * half[b]
                corners.append(p)
            out.append((np.array(corners), normal))
    return out


def _prism(radius: float, length: float) -> list[tuple[np.ndarray, np.ndarray]]:
    ang = np.linspace(0.0, 2 * math.pi, _SIDES, endpoint=False)
    ring = np.column_stack([radius * np.cos(ang), radius * np.sin(ang), np.zeros(_SIDES)])
    h = length / 2.0
    top, bottom = ring + [0, 0, h], ring + [0, 0, -h]
    out = [(top, np.array([0.0, 0.0, 1.0])), (bottom[::-1], np.array([0.0, 0.0, -1.0]))]
    for i in range(_SIDES):
        j = (i + 1) % _SIDES
        mid = (ang[i] + ang[j]) / 2
        quad = np.array([bottom[i], bottom[j], top[j], top[i]])
        out.append((quad, np.array([math.cos(mid), math.sin(mid), 0.0])))
    return out


def _shade(rgb: Sequence[float], normal: np.ndarray) -> tuple[int, int, int]:
    light = 0.55 + 0.45 * max(0.0, float(normal @ _LIGHT))
    level = round(light * SHADES) / SHADES
    return tuple(int(round(min(1.0, max(0.0, float(c))) * 255 * level)) for c in rgb[:3])  # type: ignore[return-value]


def project(points: np.ndarray) -> np.ndarray:
    """World points (n, 3) -> view coordinates (n, 2): x to the right, y up."""
    return np.column_stack([points @ _RIGHT, points @ _UP])


def scene_faces(specs: Sequence[dict[str, Any]], pos: np.ndarray, quat: np.ndarray, centre: np.ndarray,
                extent: float) -> list[Face]:  # fmt: skip
    """The faces of every body (``pos``/``quat`` rows in ``specs`` order), back to front."""
    faces: list[Face] = []
    for spec, p, q in zip(specs, pos, quat, strict=True):
        if not (np.isfinite(p).all() and np.isfinite(q).all()):
            continue
        shape, rgb = spec["shape"], spec.get("color", (0.7, 0.7, 0.7, 1.0))
        r = _rot(q)
        kind = shape["kind"]
        if kind == "plane":
            local = r.T @ (centre - p)
            half = extent
            square = np.array([[local[0] + dx * half, local[1] + dy * half, 0.0] for dx, dy in
                               ((-1, -1), (1, -1), (1, 1), (-1, 1))])  # fmt: skip
            world = square @ r.T + p
            normal = r @ np.array([0.0, 0.0, 1.0])
            faces.append(Face(float(world.mean(axis=0) @ _CAMERA), project(world), _shade(rgb, normal), floor=True))
            continue
        polys: list[tuple[np.ndarray, np.ndarray]] = []
        discs: list[tuple[np.ndarray, float]] = []
        if kind == "box":
            polys = _box(shape["size"])
        elif kind in ("cylinder", "capsule"):
            polys = _prism(float(shape["radius"]), float(shape["length"]))
            if kind == "capsule":
                h, rad = float(shape["length"]) / 2, float(shape["radius"])
                discs = [(np.array([0.0, 0.0, h]), rad), (np.array([0.0, 0.0, -h]), rad)]
        elif kind == "sphere":
            discs = [(np.zeros(3), float(shape["radius"]))]
        for corners, normal in polys:
            n_world = r @ normal
            if n_world @ _CAMERA <= 1e-9:
                continue
            world = corners @ r.T + p
            faces.append(Face(float(world.mean(axis=0) @ _CAMERA), project(world), _shade(rgb, n_world)))
        for centre_local, radius in discs:
            c = r @ centre_local + p
            faces.append(Face(float(c @ _CAMERA) + radius, project(c[None, :]), _shade(rgb, _CAMERA), radius=radius))
    faces.sort(key=lambda f: (not f.floor, f.depth))
    return faces


@dataclass(frozen=True)
class View:
    """View-coordinate bounds shared by the pictures of one case, and the scene's centre and extent."""

    x0: float
    y0: float
    x1: float
    y1: float
    centre: np.ndarray
    extent: float

    def size(self, width: int) -> tuple[int, int]:
        aspect = (self.y1 - self.y0) / (self.x1 - self.x0)
        return width, int(min(max(round(width * aspect), width * 0.45), width * 1.1))

    def to_pixels(self, points: np.ndarray, width: int, height: int) -> np.ndarray:
        scale = min(width / (self.x1 - self.x0), height / (self.y1 - self.y0))
        cx, cy = (self.x0 + self.x1) / 2, (self.y0 + self.y1) / 2
        return np.column_stack([width / 2 + (points[:, 0] - cx) * scale, height / 2 - (points[:, 1] - cy) * scale])

    def scale(self, width: int, height: int) -> float:
        return min(width / (self.x1 - self.x0), height / (self.y1 - self.y0))


def fit_view(samples: Sequence[tuple[Sequence[dict[str, Any]], np.ndarray, np.ndarray]]) -> View:
    """A view holding every moving body at every sampled pose (every non-plane body if none moves):
    ``samples`` are (specs, pos (S, N, 3), quat (S, N, 4)). Static bodies beyond it are cut off."""
    moving = any(s.get("motion") != "static" for specs, _, _ in samples for s in specs)
    pts: list[np.ndarray] = []
    for specs, pos, _quat in samples:
        for i, spec in enumerate(specs):
            if spec["shape"]["kind"] == "plane" or (moving and spec.get("motion") == "static"):
                continue
            reach = _reach(spec["shape"])
            p = pos[:, i, :]
            p = p[np.isfinite(p).all(axis=1)]
            if p.size:
                offsets = np.array([[dx, dy, dz] for dx in (-1, 1) for dy in (-1, 1) for dz in (-1, 1)]) * reach
                pts.append((p[:, None, :] + offsets[None, :, :]).reshape(-1, 3))
    cloud = np.vstack(pts) if pts else np.zeros((1, 3))
    lo, hi = cloud.min(axis=0), cloud.max(axis=0)
    centre = (lo + hi) / 2
    extent = max(float(np.max(hi - lo)) * 0.75, 1.0)
    flat = project(cloud)
    x0, y0 = flat.min(axis=0)
    x1, y1 = flat.max(axis=0)
    pad = max(x1 - x0, y1 - y0, 0.5) * 0.08
    return View(float(x0 - pad), float(y0 - pad), float(x1 + pad), float(y1 + pad), centre, extent)


def _reach(shape: dict[str, Any]) -> float:
    kind = shape["kind"]
    if kind == "box":
        return float(np.linalg.norm(shape["size"])) / 2
    if kind == "sphere":
        return float(shape["radius"])
    return float(shape["radius"]) + float(shape["length"]) / 2 + (float(shape["radius"]) if kind == "capsule" else 0)


def _hex(rgb: tuple[int, int, int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def svg_picture(faces: Sequence[Face], view: View, width: int, caption: str, label: str | None = None) -> str:
    """One picture as an ``<svg class="picture">`` titled ``caption``, with ``label`` (default: the
    caption) written in its corner."""
    w, h = view.size(width)
    out = [
        f'<svg class="picture" xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" '
        f'role="img"><title>{escape(caption)}</title><rect width="{w}" height="{h}" fill="#f4f6f8"/>'
    ]
    scale = view.scale(w, h)
    for f in faces:
        px = view.to_pixels(f.points, w, h)
        if f.radius > 0:
            out.append(f'<circle cx="{px[0, 0]:.1f}" cy="{px[0, 1]:.1f}" r="{f.radius * scale:.1f}" '
                       f'fill="{_hex(f.rgb)}" stroke="#333333" stroke-width="0.6"/>')  # fmt: skip
        else:
            pts = " ".join(f"{x:.1f},{y:.1f}" for x, y in px)
            stroke = "none" if f.floor else "#333333"
            out.append(f'<polygon points="{pts}" fill="{_hex(f.rgb)}" stroke="{stroke}" stroke-width="0.6" '
                       'stroke-linejoin="round"/>')  # fmt: skip
    out.append(f'<text x="6" y="{h - 6}" font-size="11" font-family="system-ui, sans-serif" fill="#222222">'
               f"{escape(caption if label is None else label)}</text></svg>")  # fmt: skip
    return "".join(out)
