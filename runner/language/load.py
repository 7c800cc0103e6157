"""Load a scenario file: YAML -> variant -> overrides -> parameters -> validated model -> checks.

Every problem becomes a :class:`ScenarioValidationError` naming file:line:column, the field, what was
expected and what was found. Nothing here runs user text: parameters are substituted as whole values
(runner.language.scenario_edits, with `--set` and the variant's changes).
"""

from __future__ import annotations

import copy
import hashlib
import os
import stat
from collections import ChainMap, OrderedDict
from dataclasses import dataclass, field, replace
from pathlib import Path as FsPath
from typing import Any

from pydantic import ValidationError

from runner.errors import Issue, ScenarioValidationError
from runner.language.errors_map import issues_from
from runner.language.files import special_file_kind
from runner.language.model import Scenario, Variant, VariantName
from runner.language.model_base import Strict
from runner.language.refs import check_references
from runner.language.robot_desc import ModelDesc
from runner.language.robots import load_robots
from runner.language.scenario_edits import SubstitutionBudget, apply_overrides, apply_variant, substitute
from runner.language.scenario_edits import parse_overrides as parse_overrides  # re-exported: the commands' import
from runner.language.times import time_context
from runner.language.yaml_source import MAX_FILE_BYTES, Positions, load_yaml

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
    #: the model of every entry of ``model.robots`` (runner.language.robots)
    robots: dict[str, ModelDesc] = field(default_factory=dict)


def read_source(path: FsPath, share_variants: bool = False) -> tuple[str, Any, Positions]:
    """The file's text, data and positions: a copy of their own for the caller to change; with
    ``share_variants``, the `variants` section is the parse cache's own (read it, never change it)."""
    file = str(path)
    try:
        info = os.stat(path)  # never open what is not a regular file: a FIFO or a device could block forever
    except OSError as exc:
        raise ScenarioValidationError([Issue(file, 0, 0, "", f"cannot read the file: {exc.strerror}")]) from None
    if not stat.S_ISREG(info.st_mode):
        kind = special_file_kind(info.st_mode)
        raise ScenarioValidationError([Issue(file, 0, 0, "", f"expected a scenario file, found {kind}")])
    if info.st_size > MAX_FILE_BYTES:
        message = f"file larger than {MAX_FILE_BYTES} bytes ({info.st_size} bytes); refused"
        raise ScenarioValidationError([Issue(file, 1, 1, "", message)])
    try:
        with open(path, "rb") as handle:
            raw = handle.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ScenarioValidationError([Issue(file, 0, 0, "", f"cannot read the file: {exc.strerror}")]) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        message = f"expected UTF-8 text, found a byte 0x{raw[exc.start]:02x} at offset {exc.start}"
        raise ScenarioValidationError([Issue(file, line, col, "", message)]) from None
    data, positions = _parsed(text, file, share_variants)
    if not isinstance(data, dict):
        raise ScenarioValidationError(
            [positions.issue((), f"expected a mapping at the top, found {type(data).__name__}")]
        )
    return text, data, positions


#: the parsed text of recently read files, by (file, text): a file with variants is read once to list them and
#: once per variant, and parsing is most of the loading time (61 parses for 21 files, 0.96 of 1.09 s, before
#: this). The text is the key, so an edited file is parsed again; callers get copies, since they change them.
_PARSED: OrderedDict[tuple[str, str], tuple[Any, Positions]] = OrderedDict()
_PARSED_KEPT = 8_000_000  # characters of text kept at most (hostile or generated files are large)


def _parsed(text: str, file: str, share_variants: bool = False) -> tuple[Any, Positions]:
    key = (file, text)
    hit = _PARSED.get(key)
    if hit is None:
        hit = _PARSED[key] = load_yaml(text, file)  # a refused file raises and is never kept
        while len(_PARSED) > 1 and sum(len(t) for _, t in _PARSED) > _PARSED_KEPT:
            _PARSED.popitem(last=False)
    else:
        _PARSED.move_to_end(key)
    data, kept = hit
    # the caller's changes go to a table of its own, in front of the kept one (a copy costs the file's size)
    positions = replace(kept, values=ChainMap({}, kept.values), keys=ChainMap({}, kept.keys),
                        overridden=dict(kept.overridden))  # fmt: skip
    if share_variants and isinstance(data, dict) and "variants" in data:  # each variant's load copies its own
        return {k: v if k == "variants" else copy.deepcopy(v) for k, v in data.items()}, positions
    return copy.deepcopy(data), positions  # the tables hold tuples: copying the dicts is enough


def variant_names(path: FsPath) -> list[str]:
    _, data, _ = read_source(path)
    variants = data.get("variants")
    return list(variants) if isinstance(variants, dict) and variants else [BASE_CASE]


def load_scenario(
    path: FsPath, variant: str | None = None, overrides: tuple[tuple[str, Any], ...] = ()
) -> LoadedScenario:
    """Load ``path`` as the given variant (``None``: the base case).

    The chosen variant is merged into the base and checked there; the `variants` section itself is checked
    once per file (:func:`_checked_variants`), so loading every one of n variants is linear in the file."""
    text, data, positions = read_source(path, share_variants=True)
    early = [(k, v) for k, v in overrides if k.split(".")[0] == "variants"]
    if early:  # `--set variants.x...` changes a variant before it is applied
        if "variants" in data:
            data["variants"] = copy.deepcopy(data["variants"])
        apply_overrides(data, early, positions)
    variants = data.get("variants") if isinstance(data.get("variants"), dict) else {}
    chosen = variant if variant not in (None, BASE_CASE) else None
    if chosen is not None:
        if chosen not in variants:
            names = ", ".join(variants) or "none"
            raise ScenarioValidationError(
                [positions.issue(("variants",), f"unknown variant `{chosen}`; this file has: {names}", at_key=True)]
            )
        apply_variant(data, variants[chosen], ("variants", chosen), positions)
    # after the variant: `--set` beats a variant's `set:` for the same path
    apply_overrides(data, [(k, v) for k, v in overrides if k.split(".")[0] != "variants"], positions)
    data.pop("variants", None)
    params = data.get("params") if isinstance(data.get("params"), dict) else {}
    issues: list[Issue] = []
    data = substitute(data, params, (), positions, issues, SubstitutionBudget(positions.text_size))
    if issues:
        raise ScenarioValidationError(issues)
    try:
        model = Scenario.model_validate(data, context=time_context(data))
    except ValidationError as exc:
        issues = issues_from(exc, positions, data, Scenario)
    checked, variant_issues = _checked_variants(path, text, overrides)
    if issues or variant_issues:
        raise ScenarioValidationError([*issues, *variant_issues])
    model = model.model_copy(update={"variants": checked})
    robots = load_robots(model, positions, path.parent)
    check_references(model, positions, path.parent, robots)
    return LoadedScenario(
        model=model,
        variant=chosen or BASE_CASE,
        path=path,
        text=text,
        sha256=hashlib.sha256(text.encode()).hexdigest(),
        positions=positions,
        overrides=overrides,
        robots=robots,
    )


class _VariantsSection(Strict):
    """The `variants` section alone, checked as the scenario checks it."""

    variants: dict[VariantName, Variant]


#: The checked `variants` section of recently loaded files, by (file, text, overrides): each variant is
#: checked once however many are loaded (5,000 variants, each load checking all of them: 126 s).
_VARIANTS: OrderedDict[tuple[str, str, str], tuple[dict[str, Any], list[Issue]]] = OrderedDict()


def _checked_variants(
    path: FsPath, text: str, overrides: tuple[tuple[str, Any], ...]
) -> tuple[dict[str, Any], list[Issue]]:
    """The `variants` section as models, substituted with the base's parameters (after `--set`), and its
    issues."""
    key = (str(path), text, repr(overrides))
    hit = _VARIANTS.get(key)
    if hit is not None:
        _VARIANTS.move_to_end(key)
        return hit
    data, positions = _parsed(text, str(path))
    apply_overrides(data, list(overrides), positions)
    section = data.get("variants")
    found: tuple[dict[str, Any], list[Issue]] = ({}, [])
    if section is not None:
        params = data.get("params") if isinstance(data.get("params"), dict) else {}
        issues: list[Issue] = []
        section = substitute(section, params, ("variants",), positions, issues, SubstitutionBudget(positions.text_size))
        if issues:
            found = ({}, issues)
        else:
            whole = {"variants": section}
            base = {k: v for k, v in data.items() if k != "variants"}
            context = time_context(substitute(base, params, (), positions, [], SubstitutionBudget(positions.text_size)))
            try:
                found = (_VariantsSection.model_validate(whole, context=context).variants, [])
            except ValidationError as exc:
                found = ({}, issues_from(exc, positions, whole, Scenario))
    _VARIANTS[key] = found
    while len(_VARIANTS) > 64:
        _VARIANTS.popitem(last=False)
    return found


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
