"""The names of a model file's links and joints, as the file spells them.

Any name is accepted (pybullet_data's quadrupeds name joints `8`; MJCF files name a body `pinch site`):
expressions read a name that is not an identifier by quoting it (``arm["8"].position``, docs/language.md).
The trace's message fields are identifiers, so each name has one there (:func:`field_name`: every character
other than an ASCII letter, digit or `_` becomes `_`, and `_` goes before a leading digit). What the trace
could not tell apart, or a name no reader could show, is refused at its line: an empty name, a control
character, a name given twice, and two names that become the same field.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path

from runner.language.robot_desc import ModelFileError

__all__ = ["IDENTIFIER", "check_names", "field_name", "spelled"]

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_UNSAFE = re.compile(r"[^A-Za-z0-9_]")
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")


def field_name(name: str) -> str:
    """The trace's field for a link or joint ``name``: the name itself when it is an identifier. The same rule
    as :func:`reports.trace_format.field_name` (the language may not import the reports; a test checks that
    the two agree)."""
    safe = _UNSAFE.sub("_", name)
    return f"_{safe}" if safe[:1].isdigit() else safe


def spelled(name: str) -> str:
    """``name`` as an expression writes one part of a dotted name: as it is, or quoted (``["8"]``)."""
    return f".{name}" if IDENTIFIER.fullmatch(name) else f"[{_quoted(name)}]"


def _quoted(name: str) -> str:
    return '"' + name.replace("\\", "\\\\").replace('"', '\\"') + '"'


def check_names(file: Path, kind: str, names: Iterable[tuple[str | None, int]]) -> None:
    """Refuse, at its line, the first ``kind`` (link, joint, body) name of ``names`` (each with its line, in
    file order) that is missing or empty, holds a control character, repeats one, or becomes the same trace
    field as an earlier one."""
    seen: dict[str, int] = {}
    fields: dict[str, tuple[str, int]] = {}
    for name, line in names:
        if not name:
            raise ModelFileError(file, line, f"a {kind} has no name (expected name=\"...\")", near="name=")
        if _CONTROL.search(name):
            raise ModelFileError(file, line, f"{kind} name {name!r} holds a control character")
        if name in seen:
            raise ModelFileError(
                file, line, f"{kind} name `{name}` is given twice (first at line {seen[name]})", near=f'"{name}"'
            )
        seen[name] = line
        field = field_name(name)
        if field in fields:
            other, other_line = fields[field]
            raise ModelFileError(
                file, line, f"{kind} names `{other}` (line {other_line}) and `{name}` are both `{field}` in the "
                "trace's messages, whose field names hold only letters, digits and `_`; rename one",
            )  # fmt: skip
        fields[field] = (name, line)
