"""Turn pydantic validation errors into located, readable issues."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ValidationError

from runner.errors import Issue
from runner.language.model_actions import ACTION_TAGS
from runner.language.model_assertions import ASSERTION_TAGS
from runner.language.model_walk import keys_at
from runner.language.yaml_source import Path, Positions


def _clean_loc(loc: tuple[Any, ...], data: Any, missing: bool) -> Path:
    """Keep the parts of a pydantic location that are keys or indices of the document, dropping union and type
    markers (`function-after[...]`, a tagged union's tag). A tag can also be a key of the document (`always:`
    in an assertion whose `during` is wrong), so of the readings of the location the one that follows the
    document furthest wins: the most parts followed, then the one whose last followed part is the deepest;
    on a tie, the reading that takes a part as a key before reading it as a marker. A missing field keeps its
    own name at the end.

    Each part is either followed or skipped, so there are 2**len(loc) readings (20 nested `parallel:` gave
    locations of 60 parts: minutes); the best reading of the parts from ``i`` on depends only on ``i`` and
    the node reached, so it is worked out once per (i, node): len(loc) x depth steps."""
    memo: dict[tuple[int, int], tuple[tuple[int, int], tuple[str | int, ...]]] = {}

    def best(i: int, node: Any) -> tuple[tuple[int, int], tuple[str | int, ...]]:
        """The best reading of loc[i:] from ``node``: ((parts followed, last followed index + 1, or 0), parts)."""
        if i == len(loc):
            return (0, 0), ()
        key = (i, id(node))
        if key in memo:
            return memo[key]
        part = loc[i]
        found: tuple[tuple[int, int], tuple[str | int, ...]] | None = None
        child: Any = _NOTHING
        if isinstance(node, dict) and part in node:
            child = node[part]
        elif isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
            child = node[part]
        elif missing and i == len(loc) - 1 and isinstance(part, str):
            child = None
        if child is not _NOTHING:
            (count, last), rest = best(i + 1, child)
            found = ((count + 1, last or i + 1), (part, *rest))
        skipped = best(i + 1, node)  # or read this part as a marker
        if found is None or skipped[0] > found[0]:
            found = skipped
        memo[key] = found
        return found

    return tuple(best(0, data)[1])


_NOTHING = object()


#: What a list-valued field holds, for "expected a list of ..." messages (by the field's name).
LIST_SHAPES = {
    **dict.fromkeys(
        ("pos", "vel", "angvel", "gravity", "axis", "axis2", "anchor", "value", "torque", "center", "spacing",
         "layer_shift", "start_pos"),
        "3 numbers [x, y, z]",
    ),
    **dict.fromkeys(("hpr", "start_hpr"), "3 angles [heading, pitch, roll] in degrees"),
    **dict.fromkeys(("box", "size"), "3 sizes [x, y, z]"),
    "quat": "4 numbers [w, x, y, z]",
    "color": "3 or 4 numbers [r, g, b] or [r, g, b, a]",
    "limits": "2 numbers [lo, hi] (or a mapping {lo, hi, zero, ...})",
    **dict.fromkeys(("during", "within", "time_within"), "2 times [start, end]"),
    "bodies": "2 names [body, other]",
    "contact": "2 body names [a, b]",
    "count": "3 counts [nx, ny, nz] (or one number)",
}  # fmt: skip


def _value_at(data: Any, path: Path) -> Any:
    node = data
    for part in path:
        node = node[part]
    return node


def _list_message(path: Path, value: Any, err: Any) -> str | None:
    """'expected a list of 3 numbers [x, y, z]; found 2' for a list of the wrong length, else None."""
    if not isinstance(value, list) or err["type"] not in ("missing", "too_long", "too_short"):
        return None
    field = next((p for p in reversed(path) if isinstance(p, str)), "")
    shape = LIST_SHAPES.get(field)
    if shape is None:
        wanted = (err.get("ctx") or {}).get("max_length") or (err.get("ctx") or {}).get("min_length")
        shape = f"{wanted} values" if wanted is not None else None
    if shape is None:
        return None
    return f"expected a list of {shape}; found {len(value)} item{'s' if len(value) != 1 else ''}"


def _length_message(path: Path, err: Any, value: Any) -> str | None:
    if err["type"] != "string_too_long" or not isinstance(value, str):
        return None
    limit = (err.get("ctx") or {}).get("max_length")
    what = "characters"
    if len(path) == 2 and path[0] == "variants" or path == ("scenario",):
        what = "characters (the name is part of trace file names)"
    return f"expected at most {limit} {what}; found {len(value)}"


def _found(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def issues_from(error: ValidationError, positions: Positions, data: Any, root: type[BaseModel]) -> list[Issue]:
    """Located issues, one per distinct problem, with suggestions for misspelt keys."""
    import difflib  # here: only a scenario with errors needs it (their hints)

    seen: set[Path] = set()
    issues: list[Issue] = []
    errors = error.errors(include_url=False)
    paths = [_clean_loc(tuple(err["loc"]), data, err["type"] == "missing") for err in errors]
    for err, path in zip(errors, paths, strict=True):
        kind = err["type"]
        if kind.endswith("_type") and any(len(p) > len(path) and p[: len(path)] == path for p in paths):
            # a union's other alternative (`on: {event: [actions] | handler}`): the value is of the kind whose
            # errors lie deeper, which say what is wrong with it; "should be a dictionary" there says nothing
            continue
        value = err.get("input")
        is_key = "[key]" in err["loc"]
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
        elif (listed := _list_message(path, _value_or_none(data, path), err)) is not None:
            issue = positions.issue(path, listed)
        elif kind == "missing":
            issue = positions.issue(path[:-1], f"missing required field `{path[-1]}`")
            issue = Issue(issue.file, issue.line, issue.column, _join(path), issue.message)
        elif (length := _length_message(path, err, path[-1] if is_key else _value_or_none(data, path))) is not None:
            issue = positions.issue(path, length, at_key=is_key)
        else:
            msg = err["msg"]
            if msg.startswith("Value error, "):  # our own validators' messages say what was found
                msg = msg[len("Value error, ") :]
            elif "found" not in msg:
                msg = f"{msg[0].lower()}{msg[1:]}; found {_found(value)}"
            issue = positions.issue(path, msg)
        if path not in seen:  # one issue per place: the first alternative of a union speaks for it
            seen.add(path)
            issues.append(issue)
    return issues


def _value_or_none(data: Any, path: Path) -> Any:
    try:
        return _value_at(data, path)
    except (KeyError, IndexError, TypeError):
        return None


def _join(path: Path) -> str:
    from runner.language.yaml_source import format_path

    return format_path(path)


def _is_action_path(path: Path) -> bool:
    return bool(path) and (path[0] == "on" or "func" in path or "then" in path or "else" in path)
