"""Where the camera goes: looking down at the bodies that move, from the front and a little to the side.

The direction is fixed (heading :data:`HEADING`, pitch :data:`PITCH`, in Panda3D's convention: heading
about +z from +y, pitch down negative; the lab's own camera looks along +y from (1, -8, 5) at pitch
-25), so pictures of every backend and every moment of a case are taken from one place and compare
at a glance. The distance is the smallest that keeps every sampled position of every body that moves
(plus its reach) inside the field of view with a margin; static bodies and planes are left to fall
where they fall. If nothing moves, every body that is not a plane is framed instead.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from backends.geometry import quat_matrices
from reports.scene3d.model import SceneModel

__all__ = ["HEADING", "LAB_CAMERA", "PITCH", "CameraSpec", "frame_camera", "moving_bodies", "reach"]

HEADING = 25.0  # degrees
PITCH = -25.0
FOV = (50.0, 34.0)  # horizontal, vertical degrees (a 3:2 picture)
MARGIN = 0.85  # the framed points stay within this fraction of the half field of view
MOVE_EPS = 1e-3  # metres (or radians) a body must move to count as moving


@dataclass(frozen=True)
class CameraSpec:
    """A camera: position, heading and pitch (degrees, Panda3D's hpr with roll 0), field of view."""

    pos: tuple[float, float, float]
    heading: float = HEADING
    pitch: float = PITCH
    fov: tuple[float, float] = FOV

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, forward, up) unit vectors in world coordinates."""
        return _axes(self.heading, self.pitch)

    def with_aspect(self, aspect: float) -> CameraSpec:
        """The same camera for a picture or window ``aspect`` = width / height wide: the horizontal field
        of view kept, the vertical one from it (a pinhole: tan(v/2) = tan(h/2) / aspect)."""
        v = math.degrees(2 * math.atan(math.tan(math.radians(self.fov[0] / 2)) / aspect))
        return CameraSpec(self.pos, self.heading, self.pitch, (self.fov[0], v))


#: The lab's camera (seed: "place the camera at (1,-8,5) with a pitch of -25 degrees"), with Panda3D's
#: default horizontal field of view of 40 degrees (config ``default-fov``), for a 4:3 window.
LAB_CAMERA = CameraSpec((1.0, -8.0, 5.0), 0.0, -25.0, (40.0, 40.0)).with_aspect(4 / 3)


def _axes(heading: float, pitch: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    h, p = math.radians(heading), math.radians(pitch)
    forward = np.array([-math.sin(h) * math.cos(p), math.cos(h) * math.cos(p), math.sin(p)])
    right = np.array([math.cos(h), math.sin(h), 0.0])
    up = np.cross(right, forward)
    return right, forward, up


def local_box(model: SceneModel, body: str) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) corners of the box around ``body``'s primitives in its own frame, over every scale
    the scene gives it (zero size if it has none)."""
    lows, highs = [np.zeros(3)], [np.zeros(3)]
    for _, update in model.updates:
        entity = update.get(f"body/{body}")
        if entity is None:
            continue
        for prim in entity.primitives:
            centre, half = np.asarray(prim.position, float), np.asarray(prim.size, float) / 2
            if prim.points:
                pts = np.asarray(prim.points, float) @ quat_matrices(prim.quat).T
                lows.append(pts.min(axis=0) + centre)
                highs.append(pts.max(axis=0) + centre)
            elif prim.quat == (1.0, 0.0, 0.0, 0.0):
                lows.append(centre - half)
                highs.append(centre + half)
            else:
                r = float(np.linalg.norm(half))
                lows.append(centre - r)
                highs.append(centre + r)
    return np.min(lows, axis=0), np.max(highs, axis=0)


def reach(model: SceneModel, body: str) -> float:
    """How far ``body``'s primitives extend from its origin (metres), at its largest."""
    low, high = local_box(model, body)
    return float(np.linalg.norm(np.maximum(np.abs(low), np.abs(high))))


def moving_bodies(models: Iterable[SceneModel]) -> list[str]:
    """Bodies whose recorded position or orientation changes by more than :data:`MOVE_EPS` in any run."""
    out: dict[str, None] = {}
    for model in models:
        for name, track in model.tracks.items():
            if model.shape.get(name) == "plane" or not len(track.times):
                continue
            pos = track.pos[np.isfinite(track.pos).all(axis=1)]
            quat = track.quat[np.isfinite(track.quat).all(axis=1)]
            moved = pos.size and float(np.max(np.ptp(pos, axis=0))) > MOVE_EPS
            turned = quat.size and float(np.max(np.ptp(quat, axis=0))) > MOVE_EPS
            if moved or turned:
                out[name] = None
    return list(out)


def _points(models: Sequence[SceneModel], bodies: Sequence[str], samples: int = 200) -> np.ndarray:
    """The corners of every framed body's box at sampled recorded poses, in world coordinates."""
    pts: list[np.ndarray] = []
    for model in models:
        for name in bodies:
            track = model.tracks.get(name)
            if track is None or not len(track.times):
                continue
            stride = max(1, len(track.times) // samples)
            pos = np.vstack([track.pos[::stride], track.pos[-1:]])
            quat = np.vstack([track.quat[::stride], track.quat[-1:]])
            ok = np.isfinite(pos).all(axis=1) & np.isfinite(quat).all(axis=1) & (np.abs(quat).sum(axis=1) > 0)
            if not ok.any():
                continue
            low, high = local_box(model, name)
            corners = np.array([[a[0], b[1], c[2]] for a in (low, high) for b in (low, high) for c in (low, high)])
            world = np.einsum("sij,kj->ski", quat_matrices(quat[ok]), corners) + pos[ok][:, None, :]
            pts.append(world.reshape(-1, 3))
    return np.vstack(pts) if pts else np.zeros((0, 3))


def frame_camera(models: Sequence[SceneModel], heading: float = HEADING, pitch: float = PITCH) -> CameraSpec:
    """A camera that keeps every moving body of every run in view (see the module docstring)."""
    bodies = moving_bodies(models)
    if not bodies:
        bodies = [b for m in models for b in m.bodies if m.shape.get(b) != "plane"]
    cloud = _points(models, list(dict.fromkeys(bodies)))
    if not len(cloud):
        cloud = np.zeros((1, 3))
    centre = (cloud.min(axis=0) + cloud.max(axis=0)) / 2
    right, forward, up = _axes(heading, pitch)
    rel = cloud - centre
    x, y, z = rel @ right, rel @ forward, rel @ up
    tx, tz = math.tan(math.radians(FOV[0] / 2)) * MARGIN, math.tan(math.radians(FOV[1] / 2)) * MARGIN
    # a point at depth d + y from the camera is in view while |x| <= (d + y) tx and |z| <= (d + y) tz
    need = np.maximum(np.abs(x) / tx - y, np.abs(z) / tz - y)
    distance = max(float(np.max(need)), float(np.max(-y)) + 0.5, 1.0)
    pos = centre - forward * distance
    return CameraSpec((float(pos[0]), float(pos[1]), float(pos[2])), heading, pitch)
