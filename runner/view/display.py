"""Opening Panda3D's window, or saying clearly why there is none.

Panda3D comes with the ``view`` extra (it is also the ``ode`` engine); without it, or without a display
(no ``DISPLAY`` or ``WAYLAND_DISPLAY`` on Linux, or a window Panda3D cannot open), ``scenario view``
stops with :class:`ViewUnavailable` (exit 2) before anything runs. The window is drawn by OpenGL
(``pandagl``), falling back to Panda3D's software renderer (``p3tinydisplay``, the report pictures'
renderer); ``offscreen`` draws into a buffer with the software renderer and needs no display at all
(for ``--script`` runs on a server).
"""

from __future__ import annotations

import os
import sys
from typing import Any

from runner.errors import UsageError

__all__ = ["INSTALL_HINT", "ViewUnavailable", "display_problem", "open_showbase"]

INSTALL_HINT = "pip install 'physics-scenarios[view]'"
WINDOW_SIZE = (960, 720)  # 4:3, as the lab's default camera is framed


class ViewUnavailable(UsageError):
    """There is no window to show: Panda3D is missing or there is no display (exit 2)."""


def display_problem(offscreen: bool) -> str | None:
    """Why no window can open here, or None."""
    try:
        import panda3d.core  # noqa: F401
    except ImportError:
        return f"`scenario view` needs Panda3D, which is not installed. Install it with: {INSTALL_HINT}"
    if offscreen or not sys.platform.startswith("linux"):
        return None
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return (
            "`scenario view` needs a display, and there is none here (DISPLAY is not set). Run it on a desktop, "
            "over `ssh -X`, or under a virtual display (`xvfb-run scenario view ...`); `--offscreen` with "
            "`--script` runs without one"
        )
    return None


def open_showbase(title: str, offscreen: bool, size: tuple[int, int] = WINDOW_SIZE) -> Any:
    """A ShowBase with one window (or offscreen buffer) of ``size``; ViewUnavailable if it cannot open."""
    problem = display_problem(offscreen)
    if problem:
        raise ViewUnavailable(problem)
    from panda3d.core import loadPrcFileData

    # a page loaded later wins over earlier ones (reports.scene3d.offscreen sets its own at import)
    settings = [
        f"window-title {title}",
        f"win-size {size[0]} {size[1]}",
        "load-display p3tinydisplay" if offscreen else "load-display pandagl",
        "aux-display p3tinydisplay",
        "window-type offscreen" if offscreen else "window-type onscreen",
        "notify-level-device fatal",  # no joystick folder in containers: not worth a line on every start
        "notify-level-x11display fatal",
        "notify-level-glxdisplay fatal",
        "notify-level-audio fatal",
        "audio-library-name null" if offscreen else "audio-library-name p3openal_audio",
        "sync-video true",
        "framebuffer-multisample true",
        "multisamples 4",
    ]
    loadPrcFileData("runner.view", "\n".join(settings) + "\n")
    from direct.showbase.ShowBase import ShowBase

    try:
        base = ShowBase(windowType="offscreen" if offscreen else "onscreen")
    except Exception as exc:  # ShowBase raises a bare Exception("Could not open window.")
        where = f" on display {os.environ['DISPLAY']}" if os.environ.get("DISPLAY") else ""
        raise ViewUnavailable(f"Panda3D could not open a window{where}: {exc}") from None
    if base.win is None:
        raise ViewUnavailable("Panda3D could not open a window")
    return base
