"""How failure messages show values: numbers, lists, and the member of a group an extremum comes from."""

from __future__ import annotations

import math
from typing import Any


def fmt(value: Any) -> str:
    """A value as a failure message shows it."""
    if isinstance(value, bool) or value is None:
        return str(value).lower()
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.6g}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(fmt(v) for v in value[:6]) + (", ..." if len(value) > 6 else "") + "]"
    return str(value)


def group_member(text: str, group: str, resolver: Any) -> str | None:
    """Which member of a group gives `max(group.field)` / `min(...)` (``text``): the resolver names the group's
    members (``group_members``) in the order its values are listed."""
    members = getattr(resolver, "group_members", lambda _: None)(group.partition(".")[0])
    try:
        values = resolver.value(group)
    except (KeyError, ValueError):
        return None
    if not members or not isinstance(values, list) or len(values) != len(members) or not values:
        return None
    pick = max if text.startswith("max") else min
    index = pick(range(len(values)), key=lambda i: values[i])
    return str(members[index])
