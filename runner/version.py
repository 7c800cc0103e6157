"""The tool's own version (from the installed distribution)."""

from __future__ import annotations

import functools
from importlib.metadata import PackageNotFoundError

from backends.versions import installed_version


@functools.cache  # read once per process: the command's parser and each trace's record ask for it
def tool_version() -> str:
    """``importlib.metadata.version("physics-scenarios")``, read from the metadata's header lines (the whole
    file through the e-mail parser took 1.2 ms more of every command's start-up)."""
    try:
        return installed_version("physics-scenarios")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
        return "0+unknown"
