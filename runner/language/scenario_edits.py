"""What changes a scenario's data before it is validated: `--set` overrides (dotted paths), the chosen variant's
`set`, `inputs` and `assertions`, and `${param}` substitution (whole values, within the text budget)."""

from __future__ import annotations

import copy
import re
from typing import Any

from runner.errors import Issue, ScenarioValidationError
from runner.language.yaml_source import COMMAND_LINE, MAX_TEXT, Path, Positions, format_path, load_value

_PARAM = re.compile(r"^\$\{([A-Za-z_][A-Za-z0-9_]*)\}$")
_PARAM_ANYWHERE = re.compile(r"\$\{([A-Za-z_][A-Za-z0-9_]*)\}")


def parse_overrides(items: list[str]) -> tuple[tuple[str, Any], ...]:
    """`--set key=value` items; the value is read as a YAML scalar or flow collection (plain data only).
    A refused item is an issue naming the argument."""
    out = []
    issues = []
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            issues.append(Issue(COMMAND_LINE, 0, 0, f"--set {item}", "expected KEY=VALUE, e.g. world.dt=0.01"))
            continue
        try:
            parsed = load_value(value)
        except ValueError as exc:
            issues.append(Issue(COMMAND_LINE, 0, 0, f"--set {item[:80]}", str(exc)))
            continue
        out.append((key.strip(), parsed))
    if issues:
        raise ScenarioValidationError(issues)
    return tuple(out)


#: Maps of user-chosen names: a dotted path may replace one of their entries, never create one (a typo in
#: `--set params.cont=3` must not add a parameter nobody reads).
NAME_MAPS: dict[tuple[str, ...], str] = {
    ("params",): "parameter",
    ("state",): "state variable",
    ("bodies",): "body",
    ("joints",): "joint",
    ("robots",): "robot",
    ("sounds",): "sound",
    ("intervals",): "interval",
    ("triggers",): "trigger",
    ("on",): "handler",
    ("variants",): "variant",
    ("collisions", "nodes"): "collision node",
}


class SetError(Exception):
    """A dotted path that cannot be set; the caller locates it."""


def set_path(data: dict[str, Any], dotted: str, value: Any) -> Path:
    parts: list[str | int] = [int(p) if p.isascii() and p.isdigit() else p for p in dotted.split(".")]
    if any(p == "" for p in parts):
        raise SetError(f"expected a dotted path such as world.dt, found `{dotted}`")
    node: Any = data
    for i, part in enumerate(parts):
        kind = NAME_MAPS.get(tuple(str(p) for p in parts[:i]))
        if kind is not None and isinstance(node, dict) and part not in node:
            raise SetError(unknown_name(kind, str(part), [str(k) for k in node], _NOT_DECLARED))
        last = i == len(parts) - 1
        if isinstance(node, dict):
            if last:
                node[part] = value
            else:
                node = node.setdefault(part, {})
        elif isinstance(node, list) and isinstance(part, int) and part < len(node):
            if last:
                node[part] = value
            else:
                node = node[part]
        else:
            where = format_path(tuple(parts[:i])) or "the top"
            if isinstance(node, list) and isinstance(part, int):
                problem = f"is a list of {len(node)} items, which has no index {part}"
            elif isinstance(node, list):
                problem = "is a list, not a mapping"
            else:
                problem = f"is {node!r}"[:60] + ", not a mapping"
            raise SetError(f"cannot set `{dotted}`: `{where}` {problem}")
    return tuple(parts)


def unknown_name(kind: str, name: str, known: list[str], note: str = "") -> str:
    import difflib  # here: only an unknown name needs it

    close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
    hint = f"did you mean `{close[0]}`?" if close else f"declared: {', '.join(sorted(known)) or 'none'}"
    return f"unknown {kind} `{name}`{note}; {hint}"


_NOT_DECLARED = " (a dotted path replaces a value, it does not declare one)"


class SubstitutionBudget:
    """Characters that parameter substitution may still produce (MAX_TEXT minus the document's own text)."""

    def __init__(self, used: int) -> None:
        self.left = MAX_TEXT - used

    def take(self, size: int, path: Path, positions: Positions) -> None:
        self.left -= size
        if self.left < 0:
            message = (
                f"parameter substitution makes the document hold more than {MAX_TEXT} characters of text; "
                "refused (a long parameter used many times?)"
            )
            raise ScenarioValidationError([positions.issue(path, message)])


def substitute(
    value: Any,
    params: dict[str, Any],
    path: Path,
    positions: Positions,
    issues: list[Issue],
    budget: SubstitutionBudget,
) -> Any:
    """``value`` with every `${name}` replaced: a whole-value reference by the parameter's value, one inside a
    text by its text; an unknown name is an issue (``value`` left as it is)."""
    if isinstance(value, dict):
        return {k: substitute(v, params, path + (k,), positions, issues, budget) for k, v in value.items()}
    if isinstance(value, list):
        return [substitute(v, params, path + (i,), positions, issues, budget) for i, v in enumerate(value)]
    if isinstance(value, str) and "${" in value:
        whole = _PARAM.match(value)
        names = _PARAM_ANYWHERE.findall(value)
        missing = [n for n in names if n not in params]
        if missing:
            issues.append(positions.issue(path, unknown_name("parameter", missing[0], list(params))))
            return value
        if whole:
            budget.take(len(str(params[whole.group(1)])), path, positions)
            return params[whole.group(1)]
        budget.take(sum(len(str(params[n])) for n in names), path, positions)  # checked before it is built
        return _PARAM_ANYWHERE.sub(lambda m: str(params[m.group(1)]), value)
    return value


def apply_overrides(data: dict[str, Any], overrides: list[tuple[str, Any]], positions: Positions) -> None:
    for key, value in overrides:
        argument = f"--set {key}"
        try:
            target = set_path(data, key, value)
        except SetError as exc:
            raise ScenarioValidationError([Issue(COMMAND_LINE, 0, 0, argument, str(exc))]) from None
        positions.overridden[target] = argument


def apply_variant(data: dict[str, Any], variant: Any, vpath: Path, positions: Positions) -> None:
    if not isinstance(variant, dict):
        return  # the model validation reports it
    issues = []
    for key, value in (variant.get("set") or {}).items() if isinstance(variant.get("set"), dict) else []:
        try:
            target = set_path(data, str(key), copy.deepcopy(value))
        except SetError as exc:
            issues.append(positions.issue(vpath + ("set", key), str(exc), at_key=True))
            continue
        positions.remap(vpath + ("set", key), target, value)
    if issues:
        raise ScenarioValidationError(issues)
    if "inputs" in variant and variant["inputs"] is not None:
        data["inputs"] = copy.deepcopy(variant["inputs"])
        positions.remap(vpath + ("inputs",), ("inputs",), variant["inputs"])
    extra = variant.get("assertions") or []
    if isinstance(extra, list) and extra:
        current = data.get("assertions")
        base: list[Any] = current if isinstance(current, list) else []
        offset = len(base)
        data["assertions"] = [*base, *copy.deepcopy(extra)]
        for i in range(len(extra)):
            positions.remap(vpath + ("assertions", i), ("assertions", offset + i), extra[i])
