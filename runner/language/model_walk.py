"""Walks over a scenario: which model describes a place in a document (for 'did you mean' suggestions), and every
action wherever it is written."""

from __future__ import annotations

import types
import typing
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from runner.language import model_actions as Act
from runner.language import model_behaviour as B
from runner.language.model_actions import ACTION_TAGS, tag_of
from runner.language.model_assertions import ASSERTION_TAGS, _assertion_tag
from runner.language.yaml_source import Path

if TYPE_CHECKING:
    from runner.language.model import Scenario


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
        if tag is None and B.Handler in candidates and isinstance(value, dict):
            return B.Handler  # `on: {event: {do: [...], once: true}}`
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
            value = value[part] if isinstance(value, dict | list) and _has(value, part) else None  # type: ignore[index]
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


# ---- the scenario's actions, wherever they are (handlers, interval Func steps) ----------------------
def walk_actions(actions: list[Any], path: Path) -> Iterator[tuple[Any, Path]]:
    for i, action in enumerate(actions):
        yield action, path + (i,)
        if isinstance(action, Act.IfAction):
            yield from walk_actions(action.then, path + (i, "then"))
            yield from walk_actions(action.else_, path + (i, "else"))


def walk_steps(step: B.Step, path: Path) -> Iterator[tuple[B.Step, Path]]:
    yield step, path
    for kind in ("sequence", "parallel"):
        for i, child in enumerate(getattr(step, kind) or []):
            yield from walk_steps(child, path + (kind, i))


def all_actions(model: Scenario) -> Iterator[tuple[Any, Path]]:
    for event, handler in model.on.items():
        if isinstance(handler, B.Handler):
            yield from walk_actions(handler.do, ("on", event, "do"))
        else:
            yield from walk_actions(handler, ("on", event))
    for ival, definition in model.intervals.items():
        for step, path in walk_steps(definition, ("intervals", ival)):
            if step.func is not None:
                yield from walk_actions(step.func, path + ("func",))
