"""The tool's own version (from the installed distribution)."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version


def tool_version() -> str:
    try:
        return version("physics-scenarios")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
        return "0+unknown"
