"""The window's camera: the lab's by default, orbited with the mouse about a point in front of it.

The camera looks at a pivot on its own line of sight; dragging turns it about the pivot (heading with
the horizontal motion, pitch with the vertical, pitch kept within +-89 degrees so "up" stays up), the
wheel moves it along the line of sight (between :data:`MIN_DISTANCE` and :data:`MAX_DISTANCE`). Angles in degrees,
Panda3D's convention (heading about +z from +y, pitch down negative), as reports.scene3d.CameraSpec.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from reports.scene3d.framing import CameraSpec

__all__ = ["DEGREES_PER_WINDOW", "MAX_DISTANCE", "MIN_DISTANCE", "ZOOM_STEP", "Orbit"]

DEGREES_PER_WINDOW = 180.0  # a drag across the whole window turns the camera half round
ZOOM_STEP = 0.85  # one wheel notch: the distance to the pivot times this (or divided, outwards)
MIN_DISTANCE, MAX_DISTANCE = 0.2, 500.0  # metres (the lens sees 2000 m far)


@dataclass
class Orbit:
    """A camera about ``pivot``: ``distance`` away, looking at it with ``heading`` and ``pitch``."""

    pivot: tuple[float, float, float]
    distance: float
    heading: float
    pitch: float

    @classmethod
    def looking_from(cls, spec: CameraSpec, targets: Sequence[Sequence[float]] = ()) -> Orbit:
        """Orbit about the point of ``spec``'s line of sight nearest to the centre of ``targets`` (the
        bodies' start positions), at least 1 m in front; 10 m in front when there are none."""
        _, forward, _ = spec.axes()
        pos = np.asarray(spec.pos, float)
        depth = 10.0
        if len(targets):
            centre = np.mean(np.asarray(targets, float), axis=0)
            depth = max(float((centre - pos) @ forward), 1.0)
        pivot = pos + forward * depth
        return cls((float(pivot[0]), float(pivot[1]), float(pivot[2])), depth, spec.heading, spec.pitch)

    def spec(self, fov: tuple[float, float]) -> CameraSpec:
        """The camera as a :class:`CameraSpec` (position from pivot, distance and angles)."""
        h, p = math.radians(self.heading), math.radians(self.pitch)
        forward = np.array([-math.sin(h) * math.cos(p), math.cos(h) * math.cos(p), math.sin(p)])
        pos = np.asarray(self.pivot, float) - forward * self.distance
        return CameraSpec((float(pos[0]), float(pos[1]), float(pos[2])), self.heading, self.pitch, fov)

    def drag(self, dx: float, dy: float) -> None:
        """Turn by a mouse motion of (dx, dy) in window fractions (-1..1 across the window, y up)."""
        self.heading -= dx * DEGREES_PER_WINDOW / 2
        self.pitch = min(89.0, max(-89.0, self.pitch - dy * DEGREES_PER_WINDOW / 2))

    def zoom(self, notches: int) -> None:
        """Move in (positive) or out (negative) by ``notches`` wheel notches."""
        self.distance = min(MAX_DISTANCE, max(MIN_DISTANCE, self.distance * ZOOM_STEP**notches))
