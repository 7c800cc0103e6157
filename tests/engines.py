"""The engines the tests run on, from the registry (the built-in table and the engines registered through
entry points): a new engine joins every list here without editing a test. A test about one engine in
particular names it."""

from __future__ import annotations

from backends.registry import installed_backends, list_backends

#: every listed engine, installed or not (hidden test backends excluded), in the registry's order
#: (an opt-in engine, ``BackendEntry.opt_in``, is in neither: it runs the contract suite and what names it)
ENGINES: tuple[str, ...] = tuple(e.name for e in list_backends() if not e.opt_in)
#: the listed engines installed here
INSTALLED: tuple[str, ...] = tuple(installed_backends())
