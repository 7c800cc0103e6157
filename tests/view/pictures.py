"""Finding bodies in pictures of the window: lit colours and Panda3D's own lens projection."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from reports.scene3d.framing import CameraSpec

BOX = (0.85, 0.6, 0.3)  # factory_physics.yaml's colours
DOOR = (0.45, 0.35, 0.25)


def lit_mask(image: np.ndarray, rgb: Sequence[float], levels: float = 8) -> np.ndarray:
    """Pixels that are ``rgb`` lit by some amount k in [0.3, 1.1]: k * rgb within ``levels`` of 255."""
    c = np.asarray(rgb, float) * 255
    px = image[..., :3].astype(float)
    k = (px @ c) / float(c @ c)
    return (k >= 0.3) & (k <= 1.1) & (np.abs(px - k[..., None] * c).max(axis=-1) <= levels)


def centroid(image: np.ndarray, rgb: Sequence[float]) -> tuple[float, float, int]:
    """(x, y, count) of the pixels of colour ``rgb``."""
    ys, xs = np.nonzero(lit_mask(image, rgb))
    return (float(xs.mean()) if len(xs) else np.nan, float(ys.mean()) if len(ys) else np.nan, len(xs))


def found_near(image: np.ndarray, px: Sequence[float], rgb: Sequence[float], radius: int = 4) -> bool:
    x, y = int(round(px[0])), int(round(px[1]))
    window = lit_mask(image[max(y - radius, 0) : y + radius + 1, max(x - radius, 0) : x + radius + 1], rgb)
    return bool(window.any())


def project(spec: CameraSpec, size: tuple[int, int], point: Sequence[float]) -> tuple[float, float]:
    """Pixel (x right, y down) of a world point in a ``size`` picture from ``spec``, by Panda3D's lens."""
    from panda3d.core import Camera, NodePath, PerspectiveLens, Point2, Point3

    lens = PerspectiveLens()
    lens.setFov(*spec.fov)
    root = NodePath("root")
    camera = root.attachNewNode(Camera("c", lens))
    camera.setPos(*spec.pos)
    camera.setHpr(spec.heading, spec.pitch, 0.0)
    film = Point2()
    assert lens.project(camera.getRelativePoint(root, Point3(*(float(c) for c in point))), film)
    return (film.x + 1) / 2 * size[0], (1 - film.y) / 2 * size[1]
