"""`scenario schema`: print the JSON Schema of the scenario language."""

from __future__ import annotations

import argparse
import sys

from rich.console import Console

from runner.errors import ExitCode

NAME = "schema"
HELP = "print the JSON Schema of the scenario language"


def configure(parser: argparse.ArgumentParser) -> None:
    """No arguments."""


def execute(args: argparse.Namespace, out: Console, err: Console) -> int:
    from runner.language.schema import schema_text

    sys.stdout.write(schema_text())
    return ExitCode.OK
