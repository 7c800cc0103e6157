"""Walks over a scenario: which model describes a place in a document (for 'did you mean' suggestions), and every
action wherever it is written."""

from __future__ import annotations

import types
import typing
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel
from pydantic.errors import PydanticUndefinedAnnotation

from runner.language import model_actions as Act
from runner.language import model_behaviour as B
from runner.language.model_actions import ACTION_TAGS, tag_of
from runner.language.model_assertions import ASSERTION_TAGS, _assertion_tag
from runner.language.yaml_source import Path

if TYPE_CHECKING:
    from runner.language.model import Scenario


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


def _members(annotation: Any) -> list[Any]:
    """The alternatives of a type annotation, through Annotated and unions (itself if it has none)."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _members(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [m for a in typing.get_args(annotation) for m in _members(a)]
    return [annotation]


def _model_for(annotation: Any, value: Any) -> type[BaseModel] | None:
    """The model that describes ``value`` where ``annotation`` is expected (a tagged union's member by its tag);
    None where ``value`` is no mapping (a list in a place that takes a list or a model)."""
    if not isinstance(value, dict):
        return None
    models = [m for m in _members(annotation) if isinstance(m, type) and issubclass(m, BaseModel)]
    return _pick(models, value)


def _item_type(annotation: Any, value: Any) -> Any:
    """What an item of ``value`` is expected to be where ``annotation`` is: a list's items, a dict's values (of
    the union's alternative whose container ``value`` is); None if it cannot be told."""
    for member in _members(annotation):
        origin = typing.get_origin(member)
        args = typing.get_args(member)
        if origin in (list, tuple) and isinstance(value, list) and args:
            return args[0]
        if origin is dict and isinstance(value, dict) and len(args) == 2:
            return args[1]
    return None


def _field_type(model: type[BaseModel], name: str) -> Any:
    """The field's annotation, resolved: a model whose annotations name a type defined after it (IfAction's
    `then: list[Action]`) keeps them unresolved until its validator is built, which is done here (only a
    scenario with errors asks)."""
    annotation = model.model_fields[name].annotation
    if isinstance(annotation, typing.ForwardRef | str) and not model.__pydantic_complete__:
        try:
            model.model_rebuild()
        except PydanticUndefinedAnnotation:  # a name the module does not define: no hint, as before
            return None
        annotation = model.model_fields[name].annotation
    return annotation


def keys_at(root: type[BaseModel], data: Any, path: Path) -> list[str]:
    """The keys the model at ``path`` accepts (by alias), or [] if it cannot be told. The path is followed
    through the models' fields and through lists and dicts (a handler's actions, an `if` action's branches),
    a union's alternative chosen by the document's value there."""
    annotation: Any = root
    value = data
    for part in path:
        model = _model_for(annotation, value)
        if model is not None:
            name = next((n for n, f in model.model_fields.items() if (f.alias or n) == part), None)
            if name is None:
                return []
            annotation = _field_type(model, name)
        else:
            annotation = _item_type(annotation, value)
            if annotation is None:
                return []
        value = value[part] if isinstance(value, dict | list) and _has(value, part) else None  # type: ignore[index]
    model = _model_for(annotation, value)
    return [] if model is None else [f.alias or n for n, f in model.model_fields.items()]


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
