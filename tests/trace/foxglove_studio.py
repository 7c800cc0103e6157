"""The real Foxglove Studio, headless: its npm web bundle served on 127.0.0.1, opened in Chromium over CDP.

`make foxglove` installs the bundle (npm ``@foxglove/studio-base@1.48.0``, the last open-source release,
with React 17) into ``$XDG_CACHE_HOME/physics-scenarios/foxglove-studio`` (``SCENARIO_FOXGLOVE_STUDIO``
overrides the folder). :class:`Studio` serves it with the traces and layouts from one local HTTP server
(with the Range requests Foxglove's remote-file source needs) and opens one trace after another in one
browser page, each with a layout, answering what Foxglove shows: its problems, its topic list, the Plot
legend's values, and a screenshot of the 3D panel.
"""

from __future__ import annotations

import base64
import json
import os
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from http import HTTPStatus
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote, urlsplit

from tests.reports.cdp import Browser

HOST_PAGE = Path(__file__).parent / "foxglove" / "index.html"
FLAGS = [
    "--headless", "--no-sandbox", "--no-first-run", "--disable-background-networking", "--disable-component-update",
    "--disable-sync", "--remote-debugging-port=0", "--window-size=1280,800", "--hide-scrollbars",
    "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",  # WebGL for the 3D panel
]  # fmt: skip


def bundle_folder() -> Path:
    override = os.environ.get("SCENARIO_FOXGLOVE_STUDIO")
    if override:
        return Path(override)
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "physics-scenarios" / "foxglove-studio"


def bundle_installed(folder: Path) -> bool:
    return all((folder / name).is_file() for name in ("assets/index.js", "react.production.min.js",
                                                     "react-dom.production.min.js"))  # fmt: skip


class _Handler(SimpleHTTPRequestHandler):
    """Static files from a few roots by URL prefix, with single-range requests (RFC 7233) and no caching
    of traces; quiet."""

    roots: dict[str, Path] = {}

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
        return

    def translate_path(self, path: str) -> str:
        clean = unquote(urlsplit(path).path)
        if clean == "/index.html":
            return str(HOST_PAGE)
        parts = clean.lstrip("/").split("/", 1)
        root = self.roots.get(parts[0]) if len(parts) == 2 else None
        if root is None:
            root, rest = self.roots[""], "/".join(parts)
        else:
            rest = parts[1]
        target = (root / rest).resolve()
        allowed = root.resolve() if parts[0] == "files" else root
        return str(target) if parts[0] != "files" or target.is_relative_to(allowed) else str(root / "missing")

    def send_head(self) -> Any:
        match = re.fullmatch(r"bytes=(\d*)-(\d*)", self.headers.get("Range", ""))
        path = Path(self.translate_path(self.path))
        if match is None or not path.is_file():
            return super().send_head()
        size = path.stat().st_size
        start = int(match.group(1)) if match.group(1) else max(0, size - int(match.group(2) or 0))
        end = min(int(match.group(2)), size - 1) if match.group(1) and match.group(2) else size - 1
        if start > end:
            self.send_error(HTTPStatus.REQUESTED_RANGE_NOT_SATISFIABLE)
            return None
        f = open(path, "rb")  # noqa: SIM115 - closed by copyfile's caller
        f.seek(start)
        self.send_response(HTTPStatus.PARTIAL_CONTENT)
        self.send_header("Content-Type", self.guess_type(str(path)))
        self.send_header("Content-Range", f"bytes {start}-{end}/{size}")
        self.send_header("Content-Length", str(end - start + 1))
        self.end_headers()
        self._remaining: int | None = end - start + 1
        return f

    def copyfile(self, source: Any, outputfile: Any) -> None:
        remaining = getattr(self, "_remaining", None)
        if remaining is None:
            return super().copyfile(source, outputfile)
        while remaining > 0:
            block = source.read(min(remaining, 1 << 16))
            if not block:
                break
            outputfile.write(block)
            remaining -= len(block)
        self._remaining = None

    def end_headers(self) -> None:
        self.send_header("Accept-Ranges", "bytes")
        self.send_header("Access-Control-Allow-Origin", "*")
        self.send_header("Access-Control-Expose-Headers", "Content-Length,Content-Range,Accept-Ranges")
        if not self.path.startswith("/assets/"):
            self.send_header("Cache-Control", "no-store")
        super().end_headers()


class _Server(ThreadingHTTPServer):
    daemon_threads = True

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A browser that drops a connection (a new page while a trace still streams) is not an error."""


# What the page shows, read from its DOM: the Problems tab's count, the topic list, the Plot legend rows.
_PROBE = """(() => {
  if (!document.body) return null;
  const tabs = [...document.querySelectorAll('[role="tab"]')].map(t => t.innerText.trim());
  const problems = tabs.find(t => t.startsWith('Problems'));
  const text = document.body.innerText;
  const names = [...document.querySelectorAll('[class*="plotName"]')];
  const legend = names.map(n => [n.innerText.trim(),
    (n.parentElement.querySelector('[class*="plotValue"]') || {innerText: ''}).innerText.trim()]);
  const panel = [...document.querySelectorAll('[data-testid="panel-mouseenter-container"], .mosaic-window')]
    .find(el => el.innerText.includes('Scene') && el.querySelector('canvas'));
  const canvas = panel ? panel.querySelector('canvas') : null;
  const r = canvas ? canvas.getBoundingClientRect() : null;
  const clock = document.querySelector('[data-testid="PlaybackTime-text"] input');
  const crashed = ['Something went wrong in this panel', 'This panel encountered an unexpected error']
    .filter(t => text.includes(t));
  const flagged = [...document.querySelectorAll('[class*="errorIcon"]')].length;
  return {problems: problems === undefined ? null : problems, text, legend,
          scene: r ? [r.x, r.y, r.width, r.height] : null, clock: clock ? clock.value : null,
          panelProblems: [...crashed, ...(flagged ? [`${flagged} plot paths flagged with an error`] : [])]};
})()"""

# Pixels of the screenshot in colour (saturation >= 0.15, value >= 0.1), counted in the page. The shipped
# layout hides the frames' axes and links, the grid and the background are grey, static bodies are grey:
# what has colour in the 3D panel is the scene, the bodies in their palette colours and the solids in amber.
_COUNT = """(async (png) => {
  const img = new Image(); img.src = 'data:image/png;base64,' + png; await img.decode();
  const c = document.createElement('canvas'); c.width = img.width; c.height = img.height;
  const g = c.getContext('2d'); g.drawImage(img, 0, 0);
  const d = g.getImageData(0, 0, c.width, c.height).data;
  let n = 0;
  for (let i = 0; i < d.length; i += 4) {
    const mx = Math.max(d[i], d[i + 1], d[i + 2]), mn = Math.min(d[i], d[i + 1], d[i + 2]);
    if (mx >= 26 && (mx - mn) / mx >= 0.15) n++;
  }
  return n;
})"""


@dataclass
class View:
    """What Foxglove showed for one trace."""

    url: str
    problems: int | None = None
    problem_lines: list[str] = field(default_factory=list)
    topics: set[str] = field(default_factory=set)
    legend: dict[str, str] = field(default_factory=dict)
    scene_pixels: int = 0  # coloured pixels in the 3D panel
    clock: str | None = None  # the playback time as Foxglove shows it
    panel_problems: list[str] = field(default_factory=list)  # a panel's error boundary, a plot path's error
    seconds: float = 0.0
    screenshot: bytes = b""


class Studio:
    """One server, one browser, one page: :meth:`open` loads a trace with a layout and waits until
    ``ready(view)`` holds (or ``timeout`` seconds pass)."""

    def __init__(self, bundle: Path, files: Path, profile: Path, chromium: str) -> None:
        handler = type("Handler", (_Handler,), {"roots": {"": bundle, "files": files}})
        self.server = _Server(("127.0.0.1", 0), partial(handler))
        self.port = self.server.server_address[1]
        self.files = files
        threading.Thread(target=self.server.serve_forever, daemon=True).start()
        self.browser = Browser(chromium, profile, FLAGS)
        self.browser.call("Runtime.enable")
        self.browser.call("Page.enable")
        self.browser.call("Page.navigate", url=f"http://127.0.0.1:{self.port}/index.html")
        deadline = time.monotonic() + 120
        while not self.browser.evaluate("self.studioReady === true"):
            if time.monotonic() > deadline:
                raise RuntimeError("the Foxglove Studio bundle did not load in 120 s")
            time.sleep(0.1)

    def url(self, path: Path) -> str:
        return f"http://127.0.0.1:{self.port}/files/{quote(path.resolve().relative_to(self.files.resolve()).as_posix())}"

    def open(self, trace: Path, layout: Path, ready: Callable[[View], bool], timeout: float = 60.0,
             stalled: Callable[[View], bool] | None = None, stall_seconds: float = 6.0) -> View:
        """Mount a fresh Studio on ``trace`` with ``layout`` (one page for every trace: no reload) and wait
        until ``ready(view)`` holds, ``stalled(view)`` has held for ``stall_seconds``, or ``timeout`` seconds
        pass.

        Studio 1.48 sometimes recreates its 3D renderer while it starts ("Disposing renderer" in the
        console: the renderer depends on its canvas) and the new one then never subscribes to /scene, so no
        seek brings the bodies back; mounting Studio again does. The caller decides whether to.
        """
        view = View(self.url(trace))
        stalled_since: float | None = None
        self.browser.events.clear()
        start = time.monotonic()
        self.browser.evaluate(f"self.openTrace({json.dumps(view.url)}, {json.dumps(self.url(layout))})")
        while time.monotonic() - start < timeout:
            time.sleep(0.25)
            probe = self.browser.evaluate(_PROBE)
            if probe is None:
                continue
            self._read(view, probe)
            if view.problems is None or not view.legend:
                continue
            if probe["scene"] is not None:
                view.scene_pixels = self._pixels(probe["scene"], view)
            if ready(view):
                break
            if stalled is not None and stalled(view):
                stalled_since = stalled_since or time.monotonic()
                if time.monotonic() - stalled_since >= stall_seconds:
                    break
            else:
                stalled_since = None
        view.seconds = time.monotonic() - start
        view.problem_lines = self._problem_lines()
        return view

    @staticmethod
    def _read(view: View, probe: dict[str, Any]) -> None:
        tab = probe["problems"]
        if tab is not None:
            digits = re.findall(r"\d+", tab)
            view.problems = int(digits[0]) if digits else 0
        view.topics = set(re.findall(r"^(/[\w/]+)$", probe["text"], re.M))
        view.legend = {name: value for name, value in probe["legend"]}
        view.clock = probe["clock"]
        view.panel_problems = probe["panelProblems"]

    def read(self, view: View) -> View:
        """``view`` updated with what the page shows now (legend, clock, problems)."""
        probe = self.browser.evaluate(_PROBE)
        if probe is not None:
            self._read(view, probe)
        return view

    def seek(self, seconds: float) -> None:
        """Seek as a user does: type the time into the playback time field and press Enter (with the
        "SEC" time format, the field takes seconds since the epoch: a trace's simulated seconds)."""
        field = "document.querySelector('[data-testid=\"PlaybackTime-text\"] input')"
        self.browser.evaluate(f"{field}.focus(), {field}.select()")  # focusing pauses playback
        self.browser.call("Input.insertText", text=f"{seconds:.9f}")
        self.browser.call("Input.dispatchKeyEvent", type="keyDown", key="Enter", code="Enter",
                          windowsVirtualKeyCode=13, text="\r")  # fmt: skip
        self.browser.call("Input.dispatchKeyEvent", type="keyUp", key="Enter", code="Enter", windowsVirtualKeyCode=13)
        self.browser.evaluate(f"{field}.blur()")

    def screenshot(self) -> bytes:
        """The whole page, as PNG."""
        return base64.b64decode(self.browser.call("Page.captureScreenshot", format="png")["data"])

    def _pixels(self, rect: list[float], view: View) -> int:
        x, y, w, h = rect
        shot = self.browser.call("Page.captureScreenshot", format="png",
                                 clip={"x": x, "y": y, "width": w, "height": h, "scale": 1})["data"]  # fmt: skip
        view.screenshot = base64.b64decode(shot)
        return int(self.browser.evaluate(f"({_COUNT})({json.dumps(shot)})"))

    def _problem_lines(self) -> list[str]:
        out = []
        for msg in self.browser.events:
            if msg.get("method") != "Runtime.consoleAPICalled":
                continue
            args = msg["params"].get("args", [])
            texts = [str(a.get("value", a.get("description", ""))) for a in args]
            if texts and texts[0] == "Player problem":
                out.append(" ".join(texts[1:3])[:300])
        return out

    def close(self) -> None:
        try:
            self.browser.close()
        finally:
            self.server.shutdown()
            self.server.server_close()
