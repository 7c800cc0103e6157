"""`scenario backends`: list the backends, each engine's own version (and its wrapper's), installed or not;
engines registered from outside this repository (entry points) too, a broken registration with its reason."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.table import Table

from backends.errors import BackendError
from backends.registry import DEFAULT_BACKEND, broken_backends, get_backend, is_installed, list_backends
from runner.errors import ExitCode

NAME = "backends"
HELP = "list the backends, their engines' versions and whether they are installed"


def configure(parser: argparse.ArgumentParser) -> None:
    """No arguments."""


def _engine(name: str) -> str:
    """The engine's own name and version, e.g. ``ODE 0.13.1, single precision (panda3d 1.10.16)``: asked of
    the adapter, which imports the engine."""
    try:
        return get_backend(name).engine_label()
    except BackendError as exc:
        return f"not importable: {exc}"


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    table = Table(title="backends")
    for col in ("name", "engine", "installed", "description", "install"):
        table.add_column(col)
    for entry in list_backends():
        installed = is_installed(entry.name)
        table.add_row(
            entry.name + (" (default)" if entry.name == DEFAULT_BACKEND else ""),
            _engine(entry.name) if installed else "not installed",
            "yes" if installed else "no",
            entry.description,
            "" if installed else entry.hint,
        )
    for name, reason in broken_backends().items():  # an outside engine's entry point that cannot be loaded
        table.add_row(name, "broken", "no", reason, "")
    out.print(table)
    return ExitCode.OK
