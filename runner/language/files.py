"""Which files are scenarios: the one rule the command line and the pytest plugin share.

A file is a scenario when it is ``*.yaml``/``*.yml`` and has a top-level ``schema_version:`` or ``scenario:``
key. A folder stands for every scenario under it, recursively, skipping hidden folders and pytest's default
``norecursedirs``; a file named explicitly is taken as it is (so that a broken one is reported, not skipped).
"""

from __future__ import annotations

import re
import stat
from pathlib import Path

from runner.errors import Issue, ScenarioValidationError

SCENARIO_KEY = re.compile(r"^(schema_version|scenario)\s*:", re.MULTILINE)
SUFFIXES = (".yaml", ".yml")
#: pytest's default `norecursedirs` (besides hidden folders)
SKIPPED = frozenset({"build", "dist", "node_modules", "venv", "CVS", "_darcs", "{arch}"})
_PEEK = 1_000_000  # bytes read to look for the key (the loader's size limit)


def is_scenario(path: Path) -> bool:
    """A regular ``*.yaml``/``*.yml`` file with a top-level scenario key."""
    if path.suffix not in SUFFIXES or not path.is_file():
        return False
    try:
        with open(path, "rb") as handle:
            head = handle.read(_PEEK)
    except OSError:
        return False
    return SCENARIO_KEY.search(head.decode("utf-8", "replace")) is not None


def _walk(folder: Path) -> list[Path]:
    found: list[Path] = []
    for child in sorted(folder.iterdir()):
        if child.is_dir() and not child.is_symlink():
            if not child.name.startswith(".") and child.name not in SKIPPED and not child.name.endswith(".egg"):
                found += _walk(child)
        elif is_scenario(child):
            found.append(child)
    return found


def scenario_files(paths: list[Path]) -> list[Path]:
    """Files as given (a file named twice runs twice), folders expanded; a folder without any scenario is bad
    input. A file a folder brings that is already on the list is not added again (``scenarios
    scenarios/conformance`` names each conformance file once)."""
    out: list[Path] = []
    for path in paths:
        if path.is_dir():
            found = _walk(path)
            if not found:
                message = "expected scenario files (*.yaml with `schema_version:`) in this folder, found none"
                raise ScenarioValidationError([Issue(str(path), 0, 0, "", message)])
            seen = {p.resolve() for p in out}
            out += [p for p in found if p.resolve() not in seen]
        else:
            out.append(path)
    return out


def special_file_kind(mode: int) -> str:
    """What a non-regular file is, in words."""
    for test, kind in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
    ):
        if test(mode):
            return kind
    return "a special file"
