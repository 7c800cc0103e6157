"""The Panda3D window: scenes from reports.scene3d, the orbit camera, the heads-up text, keys and clicks.

One :class:`ViewWindow` per process (Panda3D has one ShowBase). It shows one or more
:class:`reports.scene3d.PandaScene` side by side (a display region and a camera each, all moved by the
one orbit), draws the heads-up lines, turns every button event of the window into its Panda3D name
(runner.view.keys) and hands the viewer's own keys to :attr:`on_action` and the others to
:attr:`on_input`. It does not loop by itself: the caller calls :meth:`frame` (one Panda3D frame: input,
then drawing) as often as it wants pictures.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from reports.scene3d.framing import LAB_CAMERA, CameraSpec
from reports.scene3d.panda import BACKGROUND, PandaScene, software_camera_state
from runner.view.camera import Orbit
from runner.view.display import open_showbase
from runner.view.hud import Hud
from runner.view.keys import button_event, reserved_action

__all__ = ["ViewWindow"]

HUD_SCALE = 0.042
LABEL_SCALE = 0.05


class ViewWindow:
    """A window showing ``scenes`` side by side (``labels`` above each), with ``hud`` in its corner."""

    def __init__(self, title: str, scenes: Sequence[PandaScene], hud: Hud, *, offscreen: bool = False,
                 camera: CameraSpec = LAB_CAMERA, targets: Sequence[Sequence[float]] = (),
                 labels: Sequence[str] = ()) -> None:  # fmt: skip
        from direct.gui.OnscreenText import OnscreenText
        from panda3d.core import PerspectiveLens, TextNode

        self.base = base = open_showbase(title, offscreen)
        self.scenes = list(scenes)
        self.hud = hud
        self.home = camera
        self.targets = list(targets)
        self.orbit = Orbit.looking_from(camera, self.targets)
        self.closed = False
        self.solids = False
        self.on_input: Callable[[str], None] = lambda name: None
        self.on_action: Callable[[str], None] = lambda action: None
        base.disableMouse()  # the lab's first line: the camera is ours, not ShowBase's trackball
        base.setBackgroundColor(*BACKGROUND, 1.0)
        software = base.pipe.getInterfaceName() == "TinyPanda"
        base.camNode.setActive(False)
        self.cameras, self.lenses = [], []
        n = max(1, len(self.scenes))
        for i, scene in enumerate(self.scenes):
            scene.set_solids_visible(self.solids)
            scene.set_collision_visible(self.solids)
            lens = PerspectiveLens()
            lens.setNearFar(0.05, 2000.0)
            cam = base.makeCamera(base.win, displayRegion=(i / n, (i + 1) / n, 0.0, 1.0), lens=lens)
            cam.reparentTo(scene.root)  # each region draws its own scene
            if software:
                cam.node().setInitialState(software_camera_state())
            self.cameras.append(cam)
            self.lenses.append(lens)
        aspect = base.getAspectRatio()
        self.hud_text = OnscreenText(text="", parent=base.a2dTopLeft, pos=(0.03, -0.06), scale=HUD_SCALE,
                                     align=TextNode.ALeft, fg=(0.05, 0.05, 0.1, 1), bg=(1, 1, 1, 0.72),
                                     mayChange=True)  # fmt: skip
        self.labels = [
            OnscreenText(text=label, parent=base.a2dBottomLeft, scale=LABEL_SCALE, align=TextNode.ACenter,
                         pos=(aspect * 2 * (i + 0.5) / n, 0.2), fg=(0.05, 0.05, 0.1, 1), bg=(1, 1, 1, 0.72))
            for i, label in enumerate(labels)
        ]  # fmt: skip
        self._region_aspect = aspect / n
        self._drag: tuple[float, float] | None = None
        self._listen()
        self.place_camera()

    # ---- input ------------------------------------------------------------------------------------
    def _listen(self) -> None:
        base = self.base
        if base.buttonThrowers:
            thrower = base.buttonThrowers[0].node()
            thrower.setButtonDownEvent("view-down")
            thrower.setButtonRepeatEvent("view-repeat")
            thrower.setButtonUpEvent("view-up")
        for kind in ("down", "repeat", "up"):
            base.accept(f"view-{kind}", lambda button, kind=kind: self.button(button_event(kind, button)))
        if base.win is not None and hasattr(base.win, "setCloseRequestEvent"):
            base.win.setCloseRequestEvent("view-close-request")
        base.accept("view-close-request", self.close)

    def button(self, name: str) -> None:
        """One button event by its Panda3D name, from the window or from a script."""
        if name in ("wheel_up", "wheel_down"):
            self.orbit.zoom(1 if name == "wheel_up" else -1)
            self.place_camera()
        elif name == "mouse3-up":
            self._drag = None
        elif name == "mouse3" or name.endswith("-mouse3"):
            self._drag = self._mouse()
        action = reserved_action(name)
        if action is None:
            self.on_input(name)
        elif action == "close":
            self.close()
        elif action == "solids":
            self.solids = not self.solids
            for scene in self.scenes:
                scene.set_solids_visible(self.solids)
                scene.set_collision_visible(self.solids)  # a model's collision shapes with them
            self.on_action("redraw")
        elif action == "help":
            self.hud.show_help = not self.hud.show_help
        elif action == "camera":
            self.orbit = Orbit.looking_from(self.home, self.targets)
            self.place_camera()
        elif action:
            self.on_action(action)

    def _mouse(self) -> tuple[float, float] | None:
        watcher = self.base.mouseWatcherNode
        if watcher is None or not watcher.hasMouse():
            return None
        m = watcher.getMouse()
        return float(m.x), float(m.y)

    def _follow_drag(self) -> None:
        from panda3d.core import MouseButton

        watcher = self.base.mouseWatcherNode
        if self._drag is None or watcher is None:
            return
        if not watcher.isButtonDown(MouseButton.three()):
            self._drag = None
            return
        now = self._mouse()
        if now is not None:
            self.orbit.drag(now[0] - self._drag[0], now[1] - self._drag[1])
            self._drag = now
            self.place_camera()

    # ---- drawing ----------------------------------------------------------------------------------
    def camera_spec(self) -> CameraSpec:
        """Where every region's camera is now (the lens of one region)."""
        return self.orbit.spec(self.home.fov).with_aspect(self._region_aspect)

    def place_camera(self) -> None:
        spec = self.camera_spec()
        for cam, lens in zip(self.cameras, self.lenses, strict=True):
            lens.setFov(*spec.fov)
            cam.setPos(*spec.pos)
            cam.setHpr(spec.heading, spec.pitch, 0.0)

    def frame(self) -> None:
        """One Panda3D frame: input events (handled at once), the camera, the heads-up text, drawing."""
        if self.closed:
            return
        self._follow_drag()
        self.hud_text.setText("\n".join(self.hud.lines()))
        self.base.taskMgr.step()

    def screenshot(self, path: Path) -> Path:
        """The window's picture as Panda3D drew it, to a PNG file."""
        from panda3d.core import Filename

        self.base.graphicsEngine.renderFrame()
        image = self.base.win.getScreenshot()
        path.parent.mkdir(parents=True, exist_ok=True)
        image.write(Filename.fromOsSpecific(str(path)))
        return path

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        self.on_action("closed")

    def destroy(self) -> None:
        """Close the window for good (the process keeps running: the rest of a run, the recording)."""
        base: Any = self.base
        if base.win is not None:
            base.closeWindow(base.win)
            base.graphicsEngine.renderFrame()
