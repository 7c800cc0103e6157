"""The engines the tests run on, from the registry (the built-in table and the engines registered through
entry points): a new engine joins every list here without editing a test. A test about one engine in
particular names it."""

from __future__ import annotations

from backends.registry import installed_backends, list_backends

#: every listed engine, installed or not (hidden test backends excluded), in the registry's order
ENGINES: tuple[str, ...] = tuple(e.name for e in list_backends())
#: the listed engines installed here
INSTALLED: tuple[str, ...] = tuple(installed_backends())
