"""User text (a name, a description, a message from a scenario, a trace or an engine) in Markdown."""

from __future__ import annotations

import re

__all__ = ["text"]

#: the characters that can start Markdown (CommonMark and GitHub's extensions: emphasis, links, images,
#: raw HTML, entities, tables, strikethrough, math, autolinks, headings' closing ``#``)
_MARKUP = re.compile(r"([\\`*_{}\[\]<>#!|~&:@$^])")


def text(value: object) -> str:
    """``value`` as Markdown that renders as itself: one line, every character that could start markup
    backslash-escaped (also inside table cells, where ``\\|`` is GitHub's escape of the cell separator).
    Never inside a code span, where a backslash is shown as it is."""
    one_line = " ".join(str(value).splitlines()) if value is not None else ""
    return _MARKUP.sub(r"\\\1", one_line)
