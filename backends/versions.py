"""Installed distributions' versions, as ``importlib.metadata.version`` gives them, read more cheaply.

``importlib.metadata.version`` parses a distribution's whole metadata file with the e-mail parser, long
description included: MuJoCo's is thousands of lines, about 4 ms of every run's worker. The version is one of
the header lines, which end at the first blank line; only those are read here (the full parse is the fallback).
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, distribution

__all__ = ["installed_version", "version_or_absent"]


def installed_version(name: str) -> str:
    """The version of distribution ``name``; ``importlib.metadata.PackageNotFoundError`` if it is not installed."""
    dist = distribution(name)
    text = dist.read_text("METADATA") or dist.read_text("PKG-INFO") or ""
    for line in text.splitlines():
        if not line.strip():  # the end of the header lines
            break
        key, colon, value = line.partition(":")
        if colon and not key[:1].isspace() and key.strip().lower() == "version":
            return value.strip()
    return dist.version


def version_or_absent(name: str) -> str:
    """:func:`installed_version`, or "not installed" (how the registry and the adapters name a missing engine)."""
    try:
        return installed_version(name)
    except PackageNotFoundError:
        return "not installed"
