"""Times written as expressions (`at: 0.99*param.T/2`), evaluated once when the scenario is loaded.

A time, a duration or a window end may be a number, ``end`` where the field allows it, or an expression of
the scenario's parameters and constants only: ``param.<name>``, ``dt``, ``duration``, ``g``,
``gravity.x|y|z``, ``pi``, ``e``, ``inf`` and the pure functions of the expression language. Nothing that
changes during a run (a body's state, ``time``, ``state.*``, ``contact()``...) can appear there: the value
is fixed before the first step. The loader passes the names' values as pydantic's validation context
(:func:`time_context`); a field's validator calls :func:`evaluate_time`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from runner.language.expressions import ExpressionError, compile_expression

#: The names a time expression may read, for messages and docs (param.<name> besides).
TIME_NAMES = ("dt", "duration", "g", "gravity.x", "gravity.y", "gravity.z")
ALLOWED_TEXT = "param.<name>, dt, duration, g, gravity.x|y|z, pi, e, inf"


class _Names:
    """A resolver over fixed values (the time context)."""

    def __init__(self, values: Mapping[str, Any]) -> None:
        self.values = values

    def value(self, name: str) -> Any:
        return self.values[name]

    def call(self, func: str, args: Sequence[Any]) -> Any:  # pragma: no cover - refused before evaluation
        raise ExpressionError(f"{func}() cannot be used in a time")


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        return float(value)
    except OverflowError:  # an integer beyond a float (10**400): the world's own check refuses it
        return None


def time_context(data: Any) -> dict[str, Any]:
    """The values a time expression may read, from the raw document (after parameter substitution).

    A name whose source is not a valid number (``world.dt: soon``) is left out: an expression reading it is
    refused with a message saying so, next to the error on the world field itself."""
    names: dict[str, Any] = {}
    if not isinstance(data, dict):
        return {"time_names": names}
    params = data.get("params")
    if isinstance(params, dict):
        for key, value in params.items():
            if isinstance(key, str) and not isinstance(value, dict | list):
                names[f"param.{key}"] = value
    world = data.get("world")
    if isinstance(world, dict):
        for key in ("dt", "duration"):
            number = _number(world.get(key))
            if number is not None:
                names[key] = number
        gravity = world.get("gravity", [0.0, 0.0, -9.81])
        if isinstance(gravity, list) and len(gravity) == 3 and all(_number(c) is not None for c in gravity):
            gx, gy, gz = (float(c) for c in gravity)
            names.update({"gravity.x": gx, "gravity.y": gy, "gravity.z": gz})
            names["g"] = math.sqrt(gx * gx + gy * gy + gz * gz)
    return {"time_names": names}


def evaluate_time(text: str, context: Mapping[str, Any] | None) -> float:
    """The value of a time expression; :class:`ValueError` (a located field error) when it has none."""
    try:
        expr = compile_expression(text)
    except ExpressionError as exc:
        raise ValueError(str(exc)) from None
    if expr.calls:
        raise ValueError(
            f"{', '.join(sorted(expr.calls))}() cannot be used in a time: a time is fixed when the scenario is "
            f"loaded; it may read {ALLOWED_TEXT}"
        )
    values = (context or {}).get("time_names", {})
    for name in sorted(expr.names):
        if name in values:
            continue
        if name.startswith("param.") or name in TIME_NAMES:
            source = f"params.{name[6:]}" if name.startswith("param.") else f"world.{name}"
            known = "is not declared" if name.startswith("param.") else "is not a valid number"
            raise ValueError(f"cannot evaluate the time {text!r}: `{source}` {known}")
        raise ValueError(
            f"cannot use `{name}` in the time {text!r}: a time is fixed when the scenario is loaded; "
            f"it may read {ALLOWED_TEXT}"
        )
    try:
        value = expr.number(_Names(values))
    except ExpressionError as exc:
        raise ValueError(str(exc)) from None
    if not math.isfinite(value):
        raise ValueError(f"expected a finite time, found {text!r} = {value}")
    return value
