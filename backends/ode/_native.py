"""ODE's C library inside panda3d, reached with ctypes for two things panda3d.ode does not wrap.

* **Messages.** ODE reports recoverable trouble with ``dMessage`` (e.g. ``LCP internal error, s <= 0``
  from ``dWorldStep`` on big piles), whose default handler prints to the process's stderr. ``install()``
  sets ODE's message handler (``dSetMessageHandler``, process-wide) to one that keeps each message as a
  line while an adapter is open (``attach``/``detach``; otherwise it prints the line as ODE would); the
  adapter takes the lines after each of its steps and hands them to the runner through
  ``Backend.drain_messages()``. Only messages: ODE's
  error and debug handlers (``dError``, ``dDebug``, which abort the process) keep printing to stderr, so
  an abort still says why. A message's printf arguments are formatted with the C library's
  ``vsnprintf`` where a ``va_list`` travels as a pointer (x86-64, Windows, macOS); elsewhere the line
  holds the unformatted message text.
* **Version.** ODE has no version call; ``dGetConfiguration()`` tells the precision. The version is the
  one panda3d's build recipe pins: rdb/panda3d-thirdparty's CMakeLists.txt builds ODE 0.13.1 for the
  1.10 series (the library's embedded source paths, ``thirdparty/build/ode-prefix``, are that recipe's).
"""

from __future__ import annotations

import ctypes
import platform
import sys
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

#: ODE's version by panda3d series (see the module docstring).
ODE_IN_PANDA3D = {"1.10": "0.13.1"}
_BUFFER = 1024

_Handler = ctypes.CFUNCTYPE(None, ctypes.c_int, ctypes.c_char_p, ctypes.c_void_p)
_lines: list[str] = []
_state: dict[str, object] = {}  # "library", "handler": kept alive for the process's lifetime
_open = [0]  # adapters attached: while none is, a message is printed to stderr as ODE's default handler does


def _library() -> ctypes.CDLL | None:
    if "library" not in _state:
        import panda3d

        folder = Path(panda3d.__file__).parent
        found = sorted(folder.glob("libpandaode*"))
        library = None
        if found:
            try:
                library = ctypes.CDLL(str(found[0]))
            except OSError:
                library = None
        if library is not None and not hasattr(library, "dSetMessageHandler"):
            library = None
        _state["library"] = library
    lib = _state["library"]
    return lib if isinstance(lib, ctypes.CDLL) else None


def _formats_va_list() -> bool:
    """Whether a ``va_list`` argument is a pointer that can be handed on to ``vsnprintf``."""
    return sys.platform in ("win32", "darwin") or platform.machine().lower() in ("x86_64", "amd64")


def _make_handler() -> object:
    vsnprintf = None
    if _formats_va_list():
        libc = ctypes.CDLL("msvcrt" if sys.platform == "win32" else None)
        vsnprintf = libc.vsnprintf if hasattr(libc, "vsnprintf") else libc._vsnprintf
        vsnprintf.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_void_p]
        vsnprintf.restype = ctypes.c_int

    def handler(number: int, text: bytes | None, args: int | None) -> None:
        message = (text or b"").decode("utf-8", "replace")
        try:
            if vsnprintf is not None and text and b"%" in text:  # arguments to format
                buffer = ctypes.create_string_buffer(_BUFFER)
                vsnprintf(buffer, _BUFFER, text, args)
                message = buffer.value.decode("utf-8", "replace")
        except Exception:  # noqa: BLE001 - a C callback must not raise; keep the unformatted text
            pass
        line = f"ODE Message {number}: {message.strip()}"
        if _open[0]:
            _lines.append(line)
        else:  # no adapter to hand it to (panda3d.ode used directly): where ODE would have put it
            sys.stderr.write(f"\n{line}\n")

    return _Handler(handler)


def install() -> bool:
    """Route ODE's messages to :func:`take` (once per process); False if panda3d's ODE library is not found."""
    if "handler" in _state:
        return True
    lib = _library()
    if lib is None:
        return False
    handler = _make_handler()
    lib.dSetMessageHandler.argtypes = [_Handler]
    lib.dSetMessageHandler.restype = None
    lib.dSetMessageHandler(handler)
    _state["handler"] = handler
    return True


def attach() -> None:
    """An adapter opened: keep ODE's messages for it."""
    _open[0] += 1


def detach() -> None:
    """An adapter closed."""
    _open[0] = max(0, _open[0] - 1)


def take() -> list[str]:
    """The messages ODE sent since the last call."""
    out = _lines[:]
    _lines.clear()
    return out


def label() -> str:
    """``ODE 0.13.1, single precision (panda3d 1.10.16)``, as far as it can be known."""
    try:
        wrapper = version("panda3d")
    except PackageNotFoundError:
        return "not installed"
    ode = ODE_IN_PANDA3D.get(".".join(wrapper.split(".")[:2]), "(version unknown)")
    precision = ""
    lib = _library()
    if lib is not None and hasattr(lib, "dGetConfiguration"):
        lib.dGetConfiguration.restype = ctypes.c_char_p
        config = (lib.dGetConfiguration() or b"").decode()
        precision = next((f", {w[4:].replace('_', ' ')}" for w in config.split() if w.endswith("_precision")), "")
    return f"ODE {ode}{precision} (panda3d {wrapper})"
