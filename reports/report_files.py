"""Which files a report writes, and the rule that it writes and removes only its own.

A report folder (``--out``) may hold anything of the user's: the report writes ``report.json``,
``report.html``, ``report.md`` and PNG pictures in ``report-images/``, and replaces or removes a file under
those names only when it recognises the file as its own, by content, never by name alone:

* ``report.json``: a JSON object with this tool's ``generator`` and a ``report_format``;
* ``report.html``: this tool's ``<meta name="generator">`` in its first bytes;
* ``report.md``: the heading this tool starts it with;
* a picture: a PNG carrying this tool's ``Software`` text chunk (:func:`tag_png`, added to every picture
  the report writes).

A file of someone else's under one of those names refuses the whole report before anything is written
(:func:`foreign`; ``--force`` overwrites it); a picture of an earlier report that the new one does not show
is removed only when it is the tool's (a user's file in ``report-images/`` stays). Every file is written
under a fresh hidden temporary name (never an existing file) and renamed into place; when a write fails
(a full disk, a read-only folder) the temporary file is removed, so nothing half-written is left.
"""

from __future__ import annotations

import contextlib
import json
import os
import struct
import tempfile
import zlib
from collections.abc import Iterable, Mapping
from pathlib import Path

__all__ = ["GENERATOR", "HTML_MARK", "IMAGES_DIR", "MD_MARK", "NAMES", "foreign", "is_own", "refusal",
           "remove_stale_images", "tag_png", "write_file"]  # fmt: skip

GENERATOR = "physics-scenarios"
JSON_NAME, HTML_NAME, MD_NAME = "report.json", "report.html", "report.md"
NAMES = (JSON_NAME, HTML_NAME, MD_NAME)
IMAGES_DIR = "report-images"
#: in report.html's head, right after its charset
HTML_MARK = f'<meta name="generator" content="{GENERATOR}">'
#: report.md's first characters
MD_MARK = "## Backend comparison:"
_PNG = b"\x89PNG\r\n\x1a\n"
_SOFTWARE = b"Software\x00" + GENERATOR.encode() + b" report"
_HEAD = 4096  # how much of a file is read to recognise it (the JSON is read whole)


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def tag_png(data: bytes) -> bytes:
    """``data`` (a PNG) with this tool's ``Software`` text chunk after its header chunk (same pixels)."""
    if not data.startswith(_PNG) or data[12:16] != b"IHDR":
        raise ValueError("not a PNG")
    end = 8 + 12 + struct.unpack(">I", data[8:12])[0]
    return data[:end] + _chunk(b"tEXt", _SOFTWARE) + data[end:]


def _own_png(head: bytes) -> bool:
    if not head.startswith(_PNG):
        return False
    at = len(_PNG)
    while at + 8 <= len(head):
        size, kind = struct.unpack(">I", head[at : at + 4])[0], head[at + 4 : at + 8]
        if kind == b"tEXt":
            return head[at + 8 : at + 8 + size] == _SOFTWARE
        if kind == b"IDAT":
            return False
        at += 12 + size
    return False


def is_own(path: Path) -> bool:
    """``path`` (a report file or a picture) is a regular file this tool wrote (see the module docstring)."""
    if path.is_symlink() or not path.is_file():
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(_HEAD)
            if path.name == JSON_NAME:
                data = json.loads(head + f.read())
                return isinstance(data, dict) and str(data.get("generator", "")).startswith(GENERATOR) and (
                    "report_format" in data)  # fmt: skip
    except (OSError, ValueError, RecursionError):
        return False
    if path.name == HTML_NAME:
        return head.startswith(b"<!DOCTYPE html>") and HTML_MARK.encode() in head
    if path.name == MD_NAME:
        return head.startswith(MD_MARK.encode())
    return path.suffix == ".png" and _own_png(head)


def _taken(path: Path) -> bool:
    return path.exists() or path.is_symlink()


def foreign(out_dir: Path, images: Iterable[str] = ()) -> list[Path]:
    """The files under the names a report in ``out_dir`` (with pictures ``images``) would write that exist
    and are not this tool's; ``report-images`` when it is there but not a folder."""
    out_dir = Path(out_dir)
    found = [out_dir / n for n in NAMES if _taken(out_dir / n) and not is_own(out_dir / n)]
    folder = out_dir / IMAGES_DIR
    if _taken(folder) and (folder.is_symlink() or not folder.is_dir()):
        return [*found, folder]
    return found + [folder / n for n in images if _taken(folder / n) and not is_own(folder / n)]


def refusal(paths: list[Path]) -> str:
    """The message refusing to overwrite ``paths``."""
    names = ", ".join(str(p) for p in paths[:3]) + (f" and {len(paths) - 3} more" if len(paths) > 3 else "")
    one = len(paths) == 1
    return (f"{names} {'was' if one else 'were'} not written by scenario and would be overwritten; move "
            f"{'it' if one else 'them'}, choose another --out folder, or pass --force to overwrite")  # fmt: skip


def write_file(path: Path, data: str | bytes) -> None:
    """Write ``data`` under ``path`` through a new hidden temporary file beside it, renamed into place; the
    temporary file is removed when the write fails (the OSError is raised)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".partial", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data.encode("utf-8") if isinstance(data, str) else data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def remove_stale_images(folder: Path, keep: Mapping[str, bytes] | Iterable[str]) -> None:
    """Remove the pictures of an earlier report in ``folder`` that are not in ``keep`` (the tool's only)."""
    if folder.is_symlink() or not folder.is_dir():
        return
    wanted = set(keep)
    for path in sorted(folder.iterdir()):
        if path.name not in wanted and is_own(path):
            path.unlink()
