"""Find which model describes a place in a document (for 'did you mean' suggestions)."""

from __future__ import annotations

import types
import typing
from typing import Any

from pydantic import BaseModel

from runner.language.model_assertions import ASSERTION_TAGS, _assertion_tag
from runner.language.model_behaviour import ACTION_TAGS, tag_of
from runner.language.yaml_source import Path


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    """Every BaseModel class reachable inside a type annotation (unions, containers, Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    out: list[type[BaseModel]] = []
    for arg in typing.get_args(annotation):
        out.extend(_models_in(arg))
    return out


def _container(annotation: Any) -> str | None:
    """'list', 'dict' or None for the outermost container of an annotation (through Optional/Annotated)."""
    origin = typing.get_origin(annotation)
    if origin in (list, tuple):
        return "list"
    if origin is dict:
        return "dict"
    if origin in (typing.Union, types.UnionType, typing.Annotated):
        kinds = {_container(a) for a in typing.get_args(annotation)} - {None}
        return kinds.pop() if len(kinds) == 1 else None
    return None


def _pick(candidates: list[type[BaseModel]], value: Any) -> type[BaseModel] | None:
    if not candidates:
        return None
    if set(candidates) >= set(ACTION_TAGS.values()):
        tag = tag_of(value, ACTION_TAGS)
        return ACTION_TAGS.get(tag) if tag else None
    if set(candidates) >= set(ASSERTION_TAGS.values()):
        tag = _assertion_tag(value)
        return ASSERTION_TAGS.get(tag) if tag else None
    return candidates[0] if len(candidates) == 1 else None


def keys_at(root: type[BaseModel], data: Any, path: Path) -> list[str]:
    """The keys the model at ``path`` accepts (by alias), or [] if it cannot be told."""
    model: type[BaseModel] | None = root
    value = data
    annotation: Any = None
    pending_container: str | None = None
    for part in path:
        if pending_container is not None:
            value = value[part] if isinstance(value, dict | list) and _has(value, part) else None
            pending_container = None
            model = _pick(_models_in(annotation), value)
            continue
        if model is None:
            return []
        field = next((f for n, f in model.model_fields.items() if (f.alias or n) == part), None)
        if field is None:
            return []
        annotation = field.annotation
        value = value.get(part) if isinstance(value, dict) else None
        pending_container = _container(annotation)
        model = None if pending_container else _pick(_models_in(annotation), value)
    if model is None or pending_container:
        return []
    return [f.alias or n for n, f in model.model_fields.items()]


def _has(container: Any, part: Any) -> bool:
    if isinstance(container, dict):
        return part in container
    return isinstance(part, int) and 0 <= part < len(container)
