"""`scenario backends`: list the backends, their engine versions and whether they are installed."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.table import Table

from backends.registry import DEFAULT_BACKEND, engine_version, is_installed, list_backends
from runner.errors import ExitCode

NAME = "backends"
HELP = "list the backends, their versions and whether they are installed"


def configure(parser: argparse.ArgumentParser) -> None:
    """No arguments."""


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    table = Table(title="backends")
    for col in ("name", "engine version", "installed", "description", "install"):
        table.add_column(col)
    for entry in list_backends():
        installed = is_installed(entry.name)
        table.add_row(
            entry.name + (" (default)" if entry.name == DEFAULT_BACKEND else ""),
            engine_version(entry.name),
            "yes" if installed else "no",
            entry.description,
            "" if installed else entry.hint,
        )
    out.print(table)
    return ExitCode.OK
