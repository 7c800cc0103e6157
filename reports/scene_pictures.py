"""The report's pictures of a case: the scene at its key moments and a side-by-side replay, rendered by
Panda3D (reports.scene3d) into PNG through Pillow.

Every picture of a case is taken by one camera framed on the bodies that move in any of its runs, so
backends and moments compare at a glance. At each moment the backends whose pictures look the same (they
differ in at most 0.1 % of their pixels: a body a pixel or less apart) share one picture. The replay is
one PNG sheet per case (a row per backend, a column per frame) that the page shows a frame at a time:
frames side by side in one image let the PNG compressor find the parts that did not change in the
previous frame's row (about 1 kB per frame for a whole row of backends).
Each picture and frame carries where every body's centre lands in it, so a test can find each body there.

Panda3D is the ``ode`` extra; without it :func:`case_pictures` says why there are no pictures.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from PIL import Image

from backends.geometry import quat_matrices
from reports.runs import Run
from reports.scene3d.framing import CameraSpec, frame_camera, local_box
from reports.scene3d.model import SceneModel, scene_model

__all__ = ["HEIGHT", "MAX_FRAMES", "WIDTH", "CasePictures", "Picture", "Replay", "case_pictures"]

WIDTH, HEIGHT = 300, 200
MAX_FRAMES = 60
PALETTE_COLOURS = 160
INSTALL_HINT = "pip install 'physics-scenarios[ode]'"
ALIKE_LEVEL = 40  # of 255
ALIKE_PIXELS = 0.001  # of the picture


@dataclass
class Picture:
    t: float
    label: str
    backends: list[str]
    png: bytes
    bodies: dict[str, Any]  # name -> {"px": [x, y] | None, "box": [x0, y0, x1, y1] | None, "rgb", "plane": bool}


@dataclass
class Replay:
    times: list[float]
    backends: list[str]
    png: bytes  # rows: backends, columns: frames, each WIDTH x HEIGHT
    bodies: dict[str, list[list[list[float] | None]]]  # backend -> frame -> body centre per body order
    body_names: list[str]
    colours: dict[str, list[int]]


@dataclass
class CasePictures:
    pictures: list[list[Picture]] = field(default_factory=list)  # per moment, one per group of backends
    replay: Replay | None = None
    note: str = ""


@lru_cache(maxsize=1)
def _renderer() -> Any:
    from reports.scene3d.offscreen import OffscreenRenderer

    return OffscreenRenderer(WIDTH, HEIGHT)


def _png(image: Image.Image) -> bytes:
    out = io.BytesIO()
    image.save(out, "PNG", optimize=True)
    return out.getvalue()


def _rgb(model: SceneModel, body: str) -> list[int]:
    return [int(round(255 * c)) for c in model.color.get(body, (0.7, 0.7, 0.7, 1.0))[:3]]


def _footprints(renderer: Any, scene: Any, camera: CameraSpec, model: SceneModel, t: float
                ) -> list[dict[str, Any] | None]:  # fmt: skip
    """Per body (model order): where its centre lands in the picture and the pixel box around its projected
    corners (clipped to the picture); None for planes and bodies without a pose."""
    out: list[dict[str, Any] | None] = []
    for name in model.bodies:
        pose = model.pose(name, t)
        if pose is None or model.shape.get(name) == "plane":
            out.append(None)
            continue
        low, high = local_box(model, name)
        corners = np.array([[a[0], b[1], c[2]] for a in (low, high) for b in (low, high) for c in (low, high)])
        world = corners @ quat_matrices(pose[1]).T + pose[0]
        px = renderer.project(scene, camera, [pose[0], *world])
        centre = px[0] if np.isfinite(px[0]).all() else None
        seen = px[1:][np.isfinite(px[1:]).all(axis=1)]
        box = None
        if len(seen):
            lo = np.clip(seen.min(axis=0), 0, [WIDTH - 1, HEIGHT - 1])
            hi = np.clip(seen.max(axis=0), 0, [WIDTH - 1, HEIGHT - 1])
            box = [round(float(v), 1) for v in (*lo, *hi)]
        out.append({"px": None if centre is None else [round(float(centre[0]), 1), round(float(centre[1]), 1)],
                    "box": box})  # fmt: skip
    return out


def _centres(renderer: Any, scene: Any, camera: CameraSpec, model: SceneModel, t: float) -> list[list[float] | None]:
    return [f["px"] if f is not None else None for f in _footprints(renderer, scene, camera, model, t)]


def alike(a: np.ndarray, b: np.ndarray) -> bool:
    """Two pictures look the same: at most :data:`ALIKE_PIXELS` of their pixels differ by more than
    :data:`ALIKE_LEVEL` in a channel (a body moved by a pixel or less)."""
    changed = int(np.count_nonzero(np.abs(a - b).max(axis=2) > ALIKE_LEVEL))
    return changed <= ALIKE_PIXELS * a.shape[0] * a.shape[1]


def _frame_times(end: float, dt: float) -> list[float]:
    steps = int(round(end / dt)) if dt > 0 else 0
    count = min(MAX_FRAMES, steps + 1) if steps > 0 else 1
    return [round(float(t), 9) for t in np.linspace(0.0, end, count)] if count > 1 else [0.0]


def case_pictures(case: dict[str, Any], runs: dict[str, Run]) -> CasePictures:
    """Pictures at ``case["key_moments"]`` and the replay of every run in ``runs`` (backend -> run)."""
    try:
        renderer = _renderer()
        from reports.scene3d.panda import PandaScene
    except ImportError:
        return CasePictures(note=f"Pictures need Panda3D, which is not installed ({INSTALL_HINT}).")
    except RuntimeError as exc:
        return CasePictures(note=f"Pictures could not be drawn: {exc}.")
    models = {b: scene_model(r.trace) for b, r in runs.items() if r.trace is not None and r.trace.times.size}
    if not models:
        return CasePictures(note="No run recorded a step to draw.")
    camera = frame_camera(list(models.values()))
    scenes = {b: PandaScene(m) for b, m in models.items()}
    out = CasePictures()
    for moment in case["key_moments"]:
        groups: list[tuple[np.ndarray, Picture]] = []
        for backend, model in models.items():
            scene = scenes[backend]
            scene.show(moment["t"])
            image = renderer.render(scene, camera)
            pixels = np.asarray(image, dtype=np.int16)
            same = next((p for px, p in groups if alike(px, pixels)), None)
            if same is not None:
                same.backends.append(backend)
                continue
            feet = _footprints(renderer, scene, camera, model, moment["t"])
            bodies = {
                n: {**(f or {"px": None, "box": None}), "rgb": _rgb(model, n), "plane": model.shape.get(n) == "plane"}
                for n, f in zip(model.bodies, feet, strict=True)
            }
            groups.append((pixels, Picture(moment["t"], moment["label"], [backend], _png(image), bodies)))
        out.pictures.append([p for _, p in groups])
    out.replay = _replay(renderer, camera, models, scenes, case)
    return out


def _replay(renderer: Any, camera: CameraSpec, models: dict[str, SceneModel], scenes: dict[str, Any],
            case: dict[str, Any]) -> Replay:  # fmt: skip
    end = max(m.end_time for m in models.values())
    times = _frame_times(end, float(case.get("dt") or 0.0))
    backends = list(models)
    sheet = Image.new("RGB", (WIDTH * len(times), HEIGHT * len(backends)))
    centres: dict[str, list[list[list[float] | None]]] = {}
    for row, backend in enumerate(backends):
        scene, model = scenes[backend], models[backend]
        centres[backend] = []
        for col, t in enumerate(times):
            scene.show(t)
            sheet.paste(renderer.render(scene, camera), (col * WIDTH, row * HEIGHT))
            centres[backend].append(_centres(renderer, scene, camera, model, t))
    quantised = sheet.quantize(colors=PALETTE_COLOURS, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
    first = next(iter(models.values()))
    return Replay(times, backends, _png(quantised), centres, list(first.bodies),
                  {n: _rgb(first, n) for n in first.bodies})  # fmt: skip


def body_order(models: Sequence[SceneModel]) -> list[str]:
    return list(dict.fromkeys(b for m in models for b in m.bodies))
