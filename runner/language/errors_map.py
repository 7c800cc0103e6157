"""Turn pydantic validation errors into located, readable issues."""

from __future__ import annotations

import difflib
from typing import Any

from pydantic import BaseModel, ValidationError

from runner.errors import Issue
from runner.language.model_assertions import ASSERTION_TAGS
from runner.language.model_behaviour import ACTION_TAGS
from runner.language.model_walk import keys_at
from runner.language.yaml_source import Path, Positions


def _clean_loc(loc: tuple[Any, ...], data: Any, missing: bool) -> Path:
    """Keep the parts of a pydantic location that are keys or indices of the document (dropping union and
    type markers); a missing field keeps its own name at the end."""
    out: list[str | int] = []
    node = data
    for i, part in enumerate(loc):
        if isinstance(node, dict) and part in node:
            out.append(part)
            node = node[part]
        elif isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
            out.append(part)
            node = node[part]
        elif missing and i == len(loc) - 1 and isinstance(part, str):
            out.append(part)
    return tuple(out)


def _found(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def issues_from(error: ValidationError, positions: Positions, data: Any, root: type[BaseModel]) -> list[Issue]:
    """Located issues, one per distinct problem, with suggestions for misspelt keys."""
    seen: set[Path] = set()
    issues: list[Issue] = []
    for err in error.errors(include_url=False):
        kind = err["type"]
        path = _clean_loc(tuple(err["loc"]), data, kind == "missing")
        value = err.get("input")
        if kind == "extra_forbidden":
            key = str(path[-1]) if path else ""
            allowed = keys_at(root, data, path[:-1])
            close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
            hint = (
                f"; did you mean `{close[0]}`?"
                if close
                else (f"; expected one of: {', '.join(sorted(allowed))}" if allowed else "")
            )
            message = f"unknown key `{key}`{hint}"
            issue = positions.issue(path, message, at_key=True)
        elif kind in ("union_tag_not_found", "union_tag_invalid"):
            tags = ACTION_TAGS if "action" in str(err.get("ctx", "")) or _is_action_path(path) else ASSERTION_TAGS
            keys = list(value) if isinstance(value, dict) else []
            guess = next(iter(difflib.get_close_matches(keys[0], list(tags), n=1)), None) if keys else None
            what = "an action" if tags is ACTION_TAGS else "an assertion"
            message = (
                f"expected {what} with one of the keys {', '.join(tags)}; found "
                f"{'keys ' + ', '.join(map(str, keys)) if keys else _found(value)}"
            )
            if guess:
                message += f"; did you mean `{guess}`?"
            issue = positions.issue(path, message)
        elif kind == "missing":
            issue = positions.issue(path[:-1], f"missing required field `{path[-1]}`")
            issue = Issue(issue.file, issue.line, issue.column, _join(path), issue.message)
        else:
            msg = err["msg"]
            msg = msg[len("Value error, ") :] if msg.startswith("Value error, ") else msg
            if "found" not in msg:
                msg = f"{msg[0].lower()}{msg[1:]}; found {_found(value)}"
            issue = positions.issue(path, msg)
        if path not in seen:  # one issue per place: the first alternative of a union speaks for it
            seen.add(path)
            issues.append(issue)
    return issues


def _join(path: Path) -> str:
    from runner.language.yaml_source import format_path

    return format_path(path)


def _is_action_path(path: Path) -> bool:
    return bool(path) and (path[0] == "on" or "func" in path or "then" in path or "else" in path)
