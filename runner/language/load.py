"""Load a scenario file: YAML -> overrides -> variant -> parameters -> validated model -> checks.

Every problem becomes a :class:`ScenarioValidationError` naming file:line:column, the field, what was
expected and what was found. Nothing here runs user text: parameters are substituted as whole values.
"""

from __future__ import annotations

import copy
import hashlib
import re
from dataclasses import dataclass
from pathlib import Path as FsPath
from typing import Any

import yaml
from pydantic import ValidationError

from runner.errors import Issue, ScenarioValidationError
from runner.language.errors_map import issues_from
from runner.language.model import Scenario
from runner.language.refs import check_references
from runner.language.yaml_source import Path, Positions, format_path, load_yaml

_PARAM = re.compile(r"^\$\{([A-Za-z_][A-Za-z0-9_]*)\}$")
_PARAM_ANYWHERE = re.compile(r"\$\{([A-Za-z_][A-Za-z0-9_]*)\}")
BASE_CASE = "base"


@dataclass(frozen=True)
class LoadedScenario:
    """A validated scenario for one variant, with where it came from."""

    model: Scenario
    variant: str  # BASE_CASE when the file has no variants
    path: FsPath
    text: str
    sha256: str
    positions: Positions
    overrides: tuple[tuple[str, Any], ...]


def read_source(path: FsPath) -> tuple[str, Any, Positions]:
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ScenarioValidationError([Issue(str(path), 0, 0, "", f"cannot read the file: {exc.strerror}")]) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        message = f"expected UTF-8 text, found a byte 0x{raw[exc.start]:02x} at offset {exc.start}"
        raise ScenarioValidationError([Issue(str(path), line, col, "", message)]) from None
    data, positions = load_yaml(text, str(path))
    if not isinstance(data, dict):
        raise ScenarioValidationError(
            [positions.issue((), f"expected a mapping at the top, found {type(data).__name__}")]
        )
    return text, data, positions


def parse_overrides(items: list[str]) -> tuple[tuple[str, Any], ...]:
    """`--set key=value` items; the value is read as a YAML scalar or flow collection."""
    out = []
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ScenarioValidationError(
                [Issue("<command line>", 0, 0, "--set", f"expected key=value, found {item!r}")]
            )
        try:
            parsed = yaml.safe_load(value) if value.strip() else ""
        except yaml.YAMLError:
            parsed = value
        out.append((key.strip(), parsed))
    return tuple(out)


def _set_path(data: dict[str, Any], dotted: str, value: Any, file: str, origin: Path) -> Path:
    parts: list[str | int] = [int(p) if p.isdigit() else p for p in dotted.split(".")]
    node: Any = data
    for i, part in enumerate(parts[:-1]):
        if isinstance(node, dict):
            node = node.setdefault(part, {}) if parts[i + 1] != 0 else node.setdefault(part, [])
        elif isinstance(node, list) and isinstance(part, int) and part < len(node):
            node = node[part]
        else:
            raise ScenarioValidationError(
                [
                    Issue(
                        file,
                        0,
                        0,
                        dotted,
                        f"cannot set `{dotted}`: `{format_path(tuple(parts[: i + 1]))}` is not a mapping",
                    )
                ]
            )
    last = parts[-1]
    if isinstance(node, dict):
        node[last] = value
    elif isinstance(node, list) and isinstance(last, int) and last < len(node):
        node[last] = value
    else:
        raise ScenarioValidationError([Issue(file, 0, 0, dotted, f"cannot set `{dotted}`")])
    return tuple(parts)


def _substitute(value: Any, params: dict[str, Any], path: Path, positions: Positions, issues: list[Issue]) -> Any:
    if isinstance(value, dict):
        return {k: _substitute(v, params, path + (k,), positions, issues) for k, v in value.items()}
    if isinstance(value, list):
        return [_substitute(v, params, path + (i,), positions, issues) for i, v in enumerate(value)]
    if isinstance(value, str) and "${" in value:
        whole = _PARAM.match(value)
        names = _PARAM_ANYWHERE.findall(value)
        missing = [n for n in names if n not in params]
        if missing:
            issues.append(
                positions.issue(
                    path, f"unknown parameter `{missing[0]}`; declared: {', '.join(sorted(params)) or 'none'}"
                )
            )
            return value
        if whole:
            return params[whole.group(1)]
        return _PARAM_ANYWHERE.sub(lambda m: str(params[m.group(1)]), value)
    return value


def variant_names(path: FsPath) -> list[str]:
    _, data, _ = read_source(path)
    variants = data.get("variants")
    return list(variants) if isinstance(variants, dict) and variants else [BASE_CASE]


def load_scenario(
    path: FsPath, variant: str | None = None, overrides: tuple[tuple[str, Any], ...] = ()
) -> LoadedScenario:
    """Load ``path`` as the given variant (``None``: the base case)."""
    text, data, positions = read_source(path)
    data = copy.deepcopy(data)
    file = str(path)
    for key, value in overrides:
        dotted = key
        _set_path(data, dotted, value, "<command line>", ())
    variants = data.get("variants") if isinstance(data.get("variants"), dict) else {}
    chosen = variant if variant not in (None, BASE_CASE) else None
    if chosen is not None:
        if chosen not in variants:
            names = ", ".join(variants) or "none"
            raise ScenarioValidationError(
                [positions.issue(("variants",), f"unknown variant `{chosen}`; this file has: {names}", at_key=True)]
            )
        _apply_variant(data, variants[chosen], ("variants", chosen), positions, file)
    params = data.get("params") if isinstance(data.get("params"), dict) else {}
    issues: list[Issue] = []
    data = _substitute(data, params, (), positions, issues)
    if issues:
        raise ScenarioValidationError(issues)
    try:
        model = Scenario.model_validate(data)
    except ValidationError as exc:
        raise ScenarioValidationError(issues_from(exc, positions, data, Scenario)) from None
    check_references(model, positions, path.parent)
    return LoadedScenario(
        model=model,
        variant=chosen or BASE_CASE,
        path=path,
        text=text,
        sha256=hashlib.sha256(text.encode()).hexdigest(),
        positions=positions,
        overrides=overrides,
    )


def _apply_variant(data: dict[str, Any], variant: Any, vpath: Path, positions: Positions, file: str) -> None:
    if not isinstance(variant, dict):
        return  # the model validation reports it
    for key, value in (variant.get("set") or {}).items() if isinstance(variant.get("set"), dict) else []:
        target = _set_path(data, str(key), copy.deepcopy(value), file, vpath)
        positions.remap(vpath + ("set", key), target)
    if "inputs" in variant and variant["inputs"] is not None:
        data["inputs"] = copy.deepcopy(variant["inputs"])
        positions.remap(vpath + ("inputs",), ("inputs",))
    extra = variant.get("assertions") or []
    if isinstance(extra, list) and extra:
        current = data.get("assertions")
        base: list[Any] = current if isinstance(current, list) else []
        offset = len(base)
        data["assertions"] = [*base, *copy.deepcopy(extra)]
        for i in range(len(extra)):
            positions.remap(vpath + ("assertions", i), ("assertions", offset + i))


def load_all(
    path: FsPath, variant: str | None, all_variants: bool, overrides: tuple[tuple[str, Any], ...] = ()
) -> list[LoadedScenario]:
    """The cases to run: one variant, every variant, or the base case."""
    if all_variants:
        return [load_scenario(path, name, overrides) for name in variant_names(path)]
    if variant is None:
        names = variant_names(path)
        return [load_scenario(path, names[0] if names != [BASE_CASE] else None, overrides)]
    return [load_scenario(path, variant, overrides)]


def load_files(
    files: list[FsPath], variant: str | None, all_variants: bool, overrides: tuple[tuple[str, Any], ...] = ()
) -> list[LoadedScenario]:
    """The cases of several files; every file's problems are collected and raised together."""
    cases: list[LoadedScenario] = []
    issues: list[Issue] = []
    for path in files:
        try:
            cases.extend(load_all(path, variant, all_variants, overrides))
        except ScenarioValidationError as exc:
            issues.extend(exc.issues)
    if issues:
        raise ScenarioValidationError(issues)
    return cases
