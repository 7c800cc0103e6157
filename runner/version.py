"""The tool's own version (from the installed distribution)."""

from __future__ import annotations

import functools
from importlib.metadata import PackageNotFoundError, version


@functools.cache  # read once per process: the command's parser and each trace's record ask for it
def tool_version() -> str:
    try:
        return version("physics-scenarios")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
        return "0+unknown"
