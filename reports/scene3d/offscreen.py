"""Panda3D's software renderer, offscreen: pictures of a :class:`PandaScene` as Pillow images.

``p3tinydisplay`` rasterises with a z-buffer and per-vertex lighting on the CPU into an offscreen
buffer, so it needs neither a display nor a GPU and gives the same pixels on every machine for the same
Panda3D version. Its one quirk (a lit vertex colour applied twice) is corrected by a white material in
the camera's initial state. Pictures are drawn at :data:`SUPERSAMPLE` times their size and reduced with
a box filter (antialiased edges). :meth:`OffscreenRenderer.project` says where a world point lands in a
picture (Panda3D's own lens), which is how a test finds each body in it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from panda3d.core import (
    Camera,
    FrameBufferProperties,
    GraphicsEngine,
    GraphicsOutput,
    GraphicsPipe,
    GraphicsPipeSelection,
    NodePath,
    PerspectiveLens,
    Point2,
    Point3,
    Texture,
    WindowProperties,
    loadPrcFileData,
)
from PIL import Image

from reports.scene3d.framing import CameraSpec
from reports.scene3d.panda import BACKGROUND, PandaScene, software_camera_state

__all__ = ["BACKGROUND", "SUPERSAMPLE", "OffscreenRenderer", "RendererUnavailable"]

SUPERSAMPLE = 2
NEAR, FAR = 0.05, 2000.0

# before the first pipe exists: no X display is needed, and its absence is not an error worth printing
loadPrcFileData(
    "reports.scene3d",
    "load-display p3tinydisplay\nwindow-type offscreen\naudio-library-name null\n"
    "notify-level-x11display fatal\nnotify-level-display fatal\nnotify-level-device fatal\n",
)


class RendererUnavailable(RuntimeError):
    """Panda3D could not make an offscreen buffer here."""


class OffscreenRenderer:
    """One offscreen buffer of ``width`` x ``height`` pixels (as delivered) and its camera."""

    def __init__(self, width: int, height: int, *, engine: GraphicsEngine | None = None,
                 pipe: GraphicsPipe | None = None) -> None:  # fmt: skip
        self.width, self.height = int(width), int(height)
        self.engine = engine or GraphicsEngine.getGlobalPtr()
        self.pipe = pipe or GraphicsPipeSelection.getGlobalPtr().makeModulePipe("p3tinydisplay")
        if self.pipe is None:
            raise RendererUnavailable("Panda3D has no p3tinydisplay pipe")
        fb = FrameBufferProperties()
        fb.setRgbColor(True)
        fb.setDepthBits(24)
        props = WindowProperties.size(self.width * SUPERSAMPLE, self.height * SUPERSAMPLE)
        flags = GraphicsPipe.BFRefuseWindow
        self.buffer = self.engine.makeOutput(self.pipe, "reports-offscreen", 0, fb, props, flags)
        if self.buffer is None:
            raise RendererUnavailable("Panda3D could not make an offscreen buffer")
        self.buffer.setClearColorActive(True)
        self.buffer.setClearColor((*BACKGROUND, 1.0))
        self.texture = Texture("picture")
        self.buffer.addRenderTexture(self.texture, GraphicsOutput.RTMCopyRam)
        self.lens = PerspectiveLens()
        self.lens.setNearFar(NEAR, FAR)
        camera = Camera("camera", self.lens)
        camera.setInitialState(software_camera_state())
        self.camera = NodePath(camera)
        self.region = self.buffer.makeDisplayRegion()
        self.region.setCamera(self.camera)

    def close(self) -> None:
        self.engine.removeWindow(self.buffer)

    def _place(self, scene: PandaScene, spec: CameraSpec) -> None:
        self.lens.setFov(*spec.fov)
        self.camera.reparentTo(scene.root)
        self.camera.setPos(*spec.pos)
        self.camera.setHpr(spec.heading, spec.pitch, 0.0)

    def render(self, scene: PandaScene, spec: CameraSpec) -> Image.Image:
        """The scene as it is posed now, seen from ``spec``."""
        self._place(scene, spec)
        self.engine.renderFrame()
        self.engine.renderFrame()  # the copy to RAM lands after the frame that drew it
        tex = self.texture
        w, h = tex.getXSize(), tex.getYSize()
        raw = "BGRX" if tex.getNumComponents() == 4 else "BGR"  # Panda3D's RAM images are BGR(A), bottom row first
        image = Image.frombytes("RGB", (w, h), bytes(tex.getRamImage()), "raw", raw, 0, -1)
        if SUPERSAMPLE > 1:
            image = image.reduce(SUPERSAMPLE)  # the mean of each SUPERSAMPLE x SUPERSAMPLE block
        return image

    def project(self, scene: PandaScene, spec: CameraSpec, points: Sequence[Sequence[float]]) -> np.ndarray:
        """Pixel (x right, y down) of each world point in a picture from ``spec``; NaN where it is behind
        the camera or outside the picture."""
        self._place(scene, spec)
        out = np.full((len(points), 2), np.nan)
        for k, p in enumerate(points):
            local = self.camera.getRelativePoint(scene.root, Point3(*(float(c) for c in p)))
            film = Point2()
            if self.lens.project(local, film):
                out[k] = ((film.x + 1) / 2 * self.width, (1 - film.y) / 2 * self.height)
        return out
