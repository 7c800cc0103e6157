"""Typed backend options: each adapter declares its ``backend_options.<name>`` block once, as a dataclass.

A field made with :func:`option` carries its default, a one-line meaning and its bounds; the field's
annotation (``bool``, ``int``, ``float`` or ``str``, optionally ``| None``) is the type a value must
have. ``parse`` refuses unknown keys and bad values with :class:`~backends.errors.UnsupportedFeature`
naming the key, what was expected and what was received, before any engine object exists::

    @dataclass(frozen=True)
    class PyBulletOptions(BackendOptions):
        solver_iterations: int = option(50, "numSolverIterations of the constraint solver", minimum=1)

This module imports no engine, so the options of every backend can be checked without its engine.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import UnionType
from typing import Any, TypeVar, Union, get_args, get_origin, get_type_hints

from ..errors import UnsupportedFeature

_O = TypeVar("_O", bound="BackendOptions")


@dataclass(frozen=True)
class Rule:
    """How one option's value is checked (stored in the field's metadata)."""

    help: str
    minimum: float | None = None  # inclusive unless min_exclusive
    maximum: float | None = None
    min_exclusive: bool = False
    choices: tuple[str, ...] = ()
    #: A custom conversion for values no plain type describes: returns the value to keep or raises
    #: ValueError whose text says what was expected.
    convert: Callable[[Any], Any] | None = None


def option(
    default: Any,
    help: str,  # noqa: A002 - the option's one-line meaning
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    min_exclusive: bool = False,
    choices: tuple[str, ...] = (),
    convert: Callable[[Any], Any] | None = None,
) -> Any:
    """A dataclass field of a :class:`BackendOptions` (``Any`` so that it fits every annotation)."""
    rule = Rule(help, minimum, maximum, min_exclusive, choices, convert)
    return dataclasses.field(default=default, metadata={"rule": rule})


@dataclass(frozen=True)
class BackendOptions:
    """Base of every backend's options; the empty block of a backend that takes none."""

    @classmethod
    def keys(cls) -> dict[str, str]:
        """Every accepted key with its one-line meaning (for docs, ``scenario backends`` and messages)."""
        return {f.name: _rule(f).help for f in dataclasses.fields(cls)}

    @classmethod
    def parse(cls: type[_O], raw: Mapping[str, Any], backend: str) -> _O:
        """The options of ``raw`` (a scenario's ``backend_options.<backend>`` block), checked."""
        accepted = cls.keys()
        unknown = sorted(set(raw) - set(accepted))
        if unknown:
            raise UnsupportedFeature(
                f"Unknown option(s) {', '.join(unknown)} in backend_options.{backend}. "
                f"Accepted: {', '.join(sorted(accepted)) or 'none'}."
            )
        hints = get_type_hints(cls)
        values: dict[str, Any] = {}
        for f in dataclasses.fields(cls):
            if f.name in raw:
                values[f.name] = _check(f"backend_options.{backend}.{f.name}", raw[f.name], hints[f.name], _rule(f))
        return cls(**values)

    def as_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


def _rule(f: dataclasses.Field[Any]) -> Rule:
    rule = f.metadata.get("rule")
    if not isinstance(rule, Rule):
        raise TypeError(f"option `{f.name}` must be declared with backends._kit.option()")
    return rule


def _check(key: str, value: Any, kind: Any, rule: Rule) -> Any:
    """``value`` checked against the field's type and rule; UnsupportedFeature names what was expected."""
    name = key.rsplit(".", 1)[-1]

    def refuse(expected: str) -> UnsupportedFeature:
        return UnsupportedFeature(f"Invalid `{key}`. Expected {expected}. Received: {name}={value!r}.")

    optional = get_origin(kind) in (Union, UnionType) and type(None) in get_args(kind)
    if optional:
        if value is None:
            return None
        kind = next(k for k in get_args(kind) if k is not type(None))
    if rule.convert is not None:
        try:
            return rule.convert(value)
        except ValueError as exc:
            raise refuse(str(exc)) from None
    if rule.choices:
        if value not in rule.choices:
            raise refuse(f"one of {', '.join(rule.choices)}")
        return str(value)
    if kind is bool:
        if not isinstance(value, bool):
            raise refuse("true or false")
        return value
    number = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if kind is int:
        if not number or not float(value).is_integer():
            raise refuse(_bounds_text("an integer", name, rule))
        value = int(value)
    elif kind is float:
        if not number:
            raise refuse(_bounds_text("a number", name, rule))
        value = float(value)
    else:  # pragma: no cover - a declaration error, not the user's
        raise TypeError(f"option `{key}` has unsupported type {kind!r}")
    low_ok = rule.minimum is None or (value > rule.minimum if rule.min_exclusive else value >= rule.minimum)
    high_ok = rule.maximum is None or value <= rule.maximum
    if not (low_ok and high_ok):
        raise refuse(_bounds_text("an integer" if kind is int else "a number", name, rule))
    return value


def _bounds_text(what: str, name: str, rule: Rule) -> str:
    low = "" if rule.minimum is None else f"{rule.minimum:g} {'<' if rule.min_exclusive else '<='} "
    high = "" if rule.maximum is None else f" <= {rule.maximum:g}"
    return f"{what}, {low}{name}{high}" if low or high else what
