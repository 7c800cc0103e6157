"""Engines registered from outside this repository: the entry-point group ``physics_scenarios.backends``.

An installed distribution declares, in its own pyproject.toml::

    [project.entry-points."physics_scenarios.backends"]
    myengine = "my_package.registration:ENTRY"

The named object is a :class:`~backends.entry.BackendEntry`, a mapping of its fields, or a callable of no
arguments returning either; its module must not import the engine (``scenario backends`` lists engines
without importing them). The entry points are read once per process. One that cannot be loaded, that yields
something else, whose name differs from the entry point's, or that takes a built-in engine's name is
*broken*: it is left out of the listing and naming it raises :class:`BrokenBackend` with the reason
(docs/architecture.md, "An engine outside this repository").
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from importlib.metadata import EntryPoint, entry_points

from .entry import BackendEntry
from .errors import BackendError

GROUP = "physics_scenarios.backends"


class BrokenBackend(BackendError):
    """A registered engine's entry point cannot give its description (the message says which and why)."""


@dataclasses.dataclass(frozen=True)
class Registered:
    """The engines registered from outside this repository, and the entry points that could not be read."""

    entries: dict[str, BackendEntry]
    broken: dict[str, str]  # name -> the reason, naming the entry point and its distribution


def _describe(point: EntryPoint) -> str:
    dist = point.dist.name if point.dist is not None else "an unknown distribution"
    return f"entry point `{point.name} = {point.value}` (group {GROUP}, from {dist})"


def _entry(point: EntryPoint, builtin: frozenset[str]) -> BackendEntry:
    obj = point.load()
    if callable(obj) and not isinstance(obj, BackendEntry):
        obj = obj()
    if isinstance(obj, Mapping):
        fields = {f.name for f in dataclasses.fields(BackendEntry)}
        unknown = sorted(set(obj) - fields)
        if unknown:
            raise ValueError(f"unknown field(s) {', '.join(unknown)}; a backend entry has {', '.join(sorted(fields))}")
        obj = BackendEntry(**obj)
    if not isinstance(obj, BackendEntry):
        raise TypeError(f"it gives a {type(obj).__name__}, not a BackendEntry or a mapping of its fields")
    if obj.name != point.name:
        raise ValueError(f"it describes backend `{obj.name}`, not `{point.name}` (the entry point's name)")
    if obj.name in builtin:
        raise ValueError(f"`{obj.name}` is the name of a built-in backend")
    module, colon, cls = obj.target.partition(":")
    if not (module and colon and cls):
        raise ValueError(f"its target `{obj.target}` is not `module:Class`")
    package = point.dist.name if point.dist is not None else obj.distribution
    return dataclasses.replace(obj, package=obj.package or package)


def _why(exc: BaseException) -> str:
    if isinstance(exc, (ImportError, AttributeError)):
        return f"cannot be loaded ({type(exc).__name__}: {exc})."
    return f"is not a backend description: {exc}."


@functools.cache
def registered(builtin: frozenset[str]) -> Registered:
    """Every entry point of the group, described or marked broken (only the modules they name are imported)."""
    entries: dict[str, BackendEntry] = {}
    broken: dict[str, str] = {}
    for point in sorted(entry_points(group=GROUP), key=lambda p: p.name):
        try:
            if point.name in entries or point.name in broken:
                raise ValueError(f"`{point.name}` is registered by more than one entry point")
            entries[point.name] = _entry(point, builtin)
        except Exception as exc:  # whatever a third-party module raises on import is that entry's fault
            broken[point.name] = f"Backend `{point.name}` is registered but broken: its {_describe(point)} {_why(exc)}"
    return Registered(entries, broken)
