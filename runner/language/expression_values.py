"""The values of the expression language at run time: numbers kept bounded, arithmetic on numbers only, a
math error as NaN; the functions, constants and operators the grammar allows; the language's errors.

Compiling a text into an :class:`~runner.language.expressions.Expression`: :mod:`runner.language.expressions`.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable
from typing import Any

from runner.errors import ScenarioError

#: Integers stay exact up to 2**53 (a float's mantissa); a larger one becomes a float, so that no value
#: grows without bound (`floor(1e308)*floor(1e308)` would be a 2,000-bit integer, and squaring it each step
#: would take gigabytes).
MAX_EXACT_INT = 2**53


class ExpressionError(ValueError):
    """The text is not a valid expression (the message says what and where in the text)."""


class EvaluationError(ExpressionError, ScenarioError):
    """A valid expression could not be evaluated during a run (wrong types, a function of nothing...).

    A :class:`~runner.errors.ScenarioError`: the run stops, its trace is finished with status ``error``
    and the command exits with code 2, naming the expression.
    """


def _aggregate(f: Callable[..., Any]) -> Callable[..., Any]:
    def wrapped(*args: Any) -> Any:
        if len(args) == 1 and isinstance(args[0], list | tuple):
            args = tuple(args[0])
        if not args:
            raise EvaluationError(f"{f.__name__}() of nothing")
        return f(args)

    return wrapped


def bounded(value: Any) -> Any:
    """``value``, with an integer beyond :data:`MAX_EXACT_INT` turned into a float (±inf beyond the float
    range, as float arithmetic gives: ``1e308 * 10`` is inf). Anything else is returned as it is."""
    if type(value) is int and not -MAX_EXACT_INT <= value <= MAX_EXACT_INT:
        try:
            return float(value)
        except OverflowError:
            return math.inf if value > 0 else -math.inf
    return value


def _power(a: float, b: float) -> float:
    """``a ** b`` as a float: a negative base with a fractional exponent is NaN (never a complex number),
    an overflow too (through the caller); bounded in time whatever the operands."""
    return math.pow(a, b)


def is_number(value: Any) -> bool:
    """A number of the language (a bool is one: true + 1 is 2)."""
    return isinstance(value, bool | int | float)


def kind_of(value: Any) -> str:
    """What a value that is no number is, for an error message."""
    if isinstance(value, str):
        return f"text {value[:20]!r}"
    if isinstance(value, list | tuple):
        return f"a list of {len(value)} values (a body group? use max(), min(), mean()...)"
    return type(value).__name__


def _arithmetic(op: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
    """``op`` on numbers only (text or lists would repeat or concatenate: unbounded memory); a math
    error gives NaN (1/0, an overflow), like the functions below."""

    def run(a: Any, b: Any) -> Any:
        if not (is_number(a) and is_number(b)):
            raise EvaluationError(f"arithmetic needs numbers, found {kind_of(a)} and {kind_of(b)}")
        try:
            return bounded(op(bounded(a), bounded(b)))
        except (ZeroDivisionError, OverflowError, ValueError):  # ValueError: math.pow(-1, 0.5)
            return math.nan

    return run


def nan_on_math_error(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` on bounded arguments: a math error gives NaN, a wrong type an :class:`EvaluationError`."""

    def run(*args: Any) -> Any:
        try:
            return bounded(fn(*(bounded(a) for a in args)))
        except ExpressionError:
            raise
        except (ValueError, OverflowError, ZeroDivisionError):  # sqrt(-1), log(0), round(inf)...
            return math.nan
        except TypeError as exc:
            raise EvaluationError(f"{exc} (found {', '.join(kind_of(a) for a in args)})") from None

    return run


PURE_FUNCTIONS: dict[str, Callable[..., Any]] = {
    "abs": abs,
    "sqrt": math.sqrt,
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "asin": math.asin,
    "acos": math.acos,
    "atan": math.atan,
    "atan2": math.atan2,
    "exp": math.exp,
    "log": math.log,
    "hypot": math.hypot,
    "radians": math.radians,
    "degrees": math.degrees,
    "floor": math.floor,
    "ceil": math.ceil,
    "round": round,
    "sign": lambda x: (x > 0) - (x < 0),
    "min": _aggregate(min),
    "max": _aggregate(max),
    "sum": _aggregate(sum),
    "mean": _aggregate(lambda v: sum(v) / len(v)),
    "all": _aggregate(all),
    "any": _aggregate(any),
    "len": lambda v: len(v),
    "clamp": lambda x, lo, hi: max(lo, min(hi, x)),
}
#: How many arguments each function takes: (least, most); None: any number from the least.
ARITY: dict[str, tuple[int, int | None, str]] = {
    **{name: (1, 1, "x") for name in ("abs", "sqrt", "sin", "cos", "tan", "asin", "acos", "atan", "exp",
                                      "radians", "degrees", "floor", "ceil", "sign")},
    "atan2": (2, 2, "y, x"),
    "log": (1, 2, "x[, base]"),
    "round": (1, 2, "x[, digits]"),
    "hypot": (1, None, "x, y, ..."),
    **{name: (1, None, "a list, or values") for name in ("min", "max", "sum", "mean", "all", "any")},
    "len": (1, 1, "a list"),
    "clamp": (3, 3, "x, lo, hi"),
}  # fmt: skip
#: Functions the runner resolves (they need the run's state): contact(a, b), playing('ival'), count('event').
RUNNER_FUNCTIONS = frozenset({"contact", "playing", "count"})
RUNNER_ARITY = {"contact": 2, "playing": 1, "count": 1}
CONSTANTS = {"pi": math.pi, "e": math.e, "inf": math.inf, "true": True, "false": False, "True": True, "False": False}

BINARY_OPERATORS = {
    ast.Add: _arithmetic(operator.add),
    ast.Sub: _arithmetic(operator.sub),
    ast.Mult: _arithmetic(operator.mul),
    ast.Div: _arithmetic(operator.truediv),
    ast.FloorDiv: _arithmetic(operator.floordiv),
    ast.Mod: _arithmetic(operator.mod),
    ast.Pow: _arithmetic(_power),
}
COMPARISONS = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
}
