"""A minimal Language Server Protocol client over stdio, to ask `yaml-language-server` (npm) for diagnostics.

JSON-RPC messages framed by `Content-Length` headers (the LSP base protocol). The server pushes
`textDocument/publishDiagnostics` after a document is opened; it may push more than once while it loads a
schema, so :meth:`LanguageServer.diagnostics` waits until a file's diagnostics have been published and the
server answers a request sent after them (requests are answered in order, so the last push for the file has
been read by then), within a deadline.
"""

from __future__ import annotations

import json
import os
import queue
import shutil
import subprocess
import threading
import time
from pathlib import Path
from typing import IO, Any

#: Where `make editor-tools` installs the npm packages (outside the repository).
DEFAULT_PREFIX = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "physics-scenarios" / "npm"


def server_command() -> list[str] | None:
    """The yaml-language-server command, or None when it is not installed."""
    prefix = Path(os.environ.get("SCENARIO_NPM_PREFIX", DEFAULT_PREFIX))
    script = prefix / "node_modules" / "yaml-language-server" / "bin" / "yaml-language-server"
    node = shutil.which("node")
    if node is None or not script.is_file():
        return None
    return [node, str(script), "--stdio"]


class LanguageServer:
    def __init__(self, command: list[str], root: Path) -> None:
        self.process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.DEVNULL)  # fmt: skip
        self.next_id = 0
        self.messages: queue.Queue[dict[str, Any]] = queue.Queue()
        self.published: dict[str, list[dict[str, Any]]] = {}
        assert self.process.stdout is not None
        threading.Thread(target=self._read, args=(self.process.stdout,), daemon=True).start()
        self.request("initialize", {
            "processId": os.getpid(),
            "rootUri": root.as_uri(),
            "capabilities": {"textDocument": {"publishDiagnostics": {}}, "workspace": {"configuration": True}},
        })  # fmt: skip
        self.notify("initialized", {})
        self.notify("workspace/didChangeConfiguration", {"settings": {"yaml": self.settings()}})

    @staticmethod
    def settings() -> dict[str, Any]:
        return {"validate": True, "hover": True, "completion": True, "schemaStore": {"enable": False}}

    # ---- the base protocol ---------------------------------------------------------------------
    def _send(self, message: dict[str, Any]) -> None:
        body = json.dumps({"jsonrpc": "2.0", **message}).encode()
        assert self.process.stdin is not None
        self.process.stdin.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
        self.process.stdin.flush()

    def _read(self, stream: IO[bytes]) -> None:
        while True:
            length = None
            while True:
                line = stream.readline()
                if not line:
                    return
                if line in (b"\r\n", b"\n"):
                    break
                name, _, value = line.decode().partition(":")
                if name.lower() == "content-length":
                    length = int(value)
            if length is None:
                continue
            self.messages.put(json.loads(stream.read(length)))

    def notify(self, method: str, params: dict[str, Any]) -> None:
        self._send({"method": method, "params": params})

    def request(self, method: str, params: dict[str, Any], timeout: float = 60.0) -> Any:
        self.next_id += 1
        wanted = self.next_id
        self._send({"id": wanted, "method": method, "params": params})
        deadline = time.monotonic() + timeout
        while True:
            message = self._next(deadline, f"no answer to {method}")
            if message.get("id") == wanted and "method" not in message:
                return message.get("result")

    def _next(self, deadline: float, what: str) -> dict[str, Any]:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError(what)
        try:
            message = self.messages.get(timeout=left)
        except queue.Empty:
            raise TimeoutError(what) from None
        self._handle(message)
        return message

    def _handle(self, message: dict[str, Any]) -> None:
        method = message.get("method")
        if method == "textDocument/publishDiagnostics":
            self.published[message["params"]["uri"]] = message["params"]["diagnostics"]
        elif method is not None and "id" in message:  # a request from the server: configuration, etc.
            result: Any = None
            if method == "workspace/configuration":
                result = [self.settings() for _ in message["params"].get("items", [])]
            self._send({"id": message["id"], "result": result})

    # ---- what the tests use ------------------------------------------------------------------------
    def open(self, path: Path) -> str:
        uri = path.resolve().as_uri()
        self.published.pop(uri, None)
        self.notify("textDocument/didOpen", {
            "textDocument": {"uri": uri, "languageId": "yaml", "version": 1, "text": path.read_text()},
        })  # fmt: skip
        return uri

    def diagnostics(self, uri: str, timeout: float = 60.0) -> list[dict[str, Any]]:
        """The file's diagnostics once the server has published them and answered a later request."""
        deadline = time.monotonic() + timeout
        while uri not in self.published:
            self._next(deadline, f"no diagnostics for {uri}")
        self.request("textDocument/hover", {"textDocument": {"uri": uri}, "position": {"line": 0, "character": 0}},
                     timeout=max(1.0, deadline - time.monotonic()))  # fmt: skip
        return self.published[uri]

    def close(self) -> None:
        try:
            self.request("shutdown", {}, timeout=10)
            self.notify("exit", {})
            self.process.wait(timeout=10)
        except (TimeoutError, OSError, subprocess.TimeoutExpired):
            self.process.kill()
            self.process.wait()
