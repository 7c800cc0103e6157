"""A small, safe expression language for conditions and assertions.

Syntax is a subset of Python's: numbers, ``true``/``false`` (and True/False), strings, ``+ - * / // % **``,
comparisons (chains allowed), ``and or not``, ``x if c else y``, parentheses, calls to a fixed list of
functions, and dotted names such as ``box.pos.z``, ``slider.position``, ``state.door_open``,
``param.count``, ``time``, ``dt``; a part that is not an identifier (a robot's joint named ``8``) is quoted:
``arm["8"].position`` reads the name ``arm.8.position``. Text is parsed with :mod:`ast` and every node is
checked against a whitelist, then compiled into plain Python closures: nothing is ever passed to
``eval``/``exec``; attribute access on values is impossible (dotted names are resolved by the runner as
whole names); unquoted names starting with an underscore are refused.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from runner.errors import ScenarioError
from runner.language.explain import fmt, group_member

MAX_LENGTH = 2000
MAX_NODES = 500
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


class Resolver(Protocol):
    def value(self, name: str) -> Any: ...  # a dotted name, e.g. "box.pos.z"
    def call(self, func: str, args: Sequence[Any]) -> Any: ...  # runner-level functions (contact, playing...)


@dataclass(frozen=True)
class _Part:
    """A sub-expression shown when a condition fails: its text and how to evaluate it."""

    text: str
    fn: Callable[[Resolver], Any]
    extremum_of: str | None = None  # `max(crate.speed)`: the group's dotted name, to name the member


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


def _is_number(value: Any) -> bool:
    return isinstance(value, bool | int | float)


def _kind(value: Any) -> str:
    if isinstance(value, str):
        return f"text {value[:20]!r}"
    if isinstance(value, list | tuple):
        return f"a list of {len(value)} values (a body group? use max(), min(), mean()...)"
    return type(value).__name__


def _arithmetic(op: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
    """``op`` on numbers only (text or lists would repeat or concatenate: unbounded memory); a math
    error gives NaN (1/0, an overflow), like the functions below."""

    def run(a: Any, b: Any) -> Any:
        if not (_is_number(a) and _is_number(b)):
            raise EvaluationError(f"arithmetic needs numbers, found {_kind(a)} and {_kind(b)}")
        try:
            return bounded(op(bounded(a), bounded(b)))
        except (ZeroDivisionError, OverflowError, ValueError):  # ValueError: math.pow(-1, 0.5)
            return math.nan

    return run


def _nan_on_math_error(fn: Callable[..., Any]) -> Callable[..., Any]:
    def run(*args: Any) -> Any:
        try:
            return bounded(fn(*(bounded(a) for a in args)))
        except ExpressionError:
            raise
        except (ValueError, OverflowError, ZeroDivisionError):  # sqrt(-1), log(0), round(inf)...
            return math.nan
        except TypeError as exc:
            raise EvaluationError(f"{exc} (found {', '.join(_kind(a) for a in args)})") from None

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

_BIN = {
    ast.Add: _arithmetic(operator.add),
    ast.Sub: _arithmetic(operator.sub),
    ast.Mult: _arithmetic(operator.mul),
    ast.Div: _arithmetic(operator.truediv),
    ast.FloorDiv: _arithmetic(operator.floordiv),
    ast.Mod: _arithmetic(operator.mod),
    ast.Pow: _arithmetic(_power),
}
_CMP = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
}

Evaluator = Callable[[Resolver], Any]


@dataclass(frozen=True)
class Expression:
    """A compiled expression: call :meth:`evaluate` with a resolver."""

    text: str
    names: frozenset[str]  # dotted names it reads
    calls: frozenset[str]  # runner functions it calls
    _fn: Evaluator
    call_args: frozenset[tuple[str, tuple[str, ...]]] = frozenset()  # (function, literal arguments)
    parts: tuple[_Part, ...] = ()  # sub-expressions, for explain()

    def explain(self, resolver: Resolver, limit: int = 8) -> str:
        """The values of the sub-expressions now, like pytest's assertion rewriting: `box.pos.z = 0.12,
        max(crate.speed) = 0.031 (crate_4)`; parts that cannot be evaluated are left out."""
        shown: list[str] = []
        for part in self.parts[:limit]:
            try:
                value = part.fn(resolver)
            except (ExpressionError, TypeError, ValueError, ArithmeticError, KeyError):
                continue
            text = f"{part.text} = {fmt(value)}"
            member = group_member(part.text, part.extremum_of, resolver) if part.extremum_of is not None else None
            shown.append(text + (f" ({member})" if member else ""))
        return ", ".join(shown)

    def evaluate(self, resolver: Resolver) -> Any:
        try:
            return self._fn(resolver)
        except EvaluationError as exc:
            raise EvaluationError(f"cannot evaluate {self.text!r}: {exc}") from None
        except (TypeError, ExpressionError) as exc:  # e.g. `1 < 'a'`, comparing a number with text
            raise EvaluationError(f"cannot evaluate {self.text!r}: {exc}") from None
        except (ZeroDivisionError, OverflowError, ValueError):
            return math.nan

    def truth(self, resolver: Resolver) -> bool:
        """The value as a condition: NaN (a failed operation) is false; text or a list is an error."""
        value = self.evaluate(resolver)
        if not _is_number(value):
            raise EvaluationError(f"cannot evaluate {self.text!r}: expected true or false, found {_kind(value)}")
        return bool(value) and not (isinstance(value, float) and math.isnan(value))

    def number(self, resolver: Resolver) -> float:
        value = self.evaluate(resolver)
        if not _is_number(value):
            raise EvaluationError(f"cannot evaluate {self.text!r}: expected a number, found {_kind(value)}")
        return float(bounded(value))


def _parts(node: ast.AST) -> list[tuple[str, bool]] | None:
    """The parts of a dotted name, each with whether it was quoted (``arm["8"].position``: a robot's link or
    joint whose name is not an identifier), first part first; None if ``node`` is no name."""
    parts: list[tuple[str, bool]] = []
    while isinstance(node, ast.Attribute | ast.Subscript):
        if isinstance(node, ast.Attribute):
            parts.append((node.attr, False))
        elif isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str):
            parts.append((node.slice.value, True))
        else:
            return None
        node = node.value
    if isinstance(node, ast.Name):
        parts.append((node.id, False))
        return parts[::-1]
    return None


def _dotted(node: ast.AST) -> str | None:
    parts = _parts(node)
    return None if parts is None else ".".join(part for part, _ in parts)


def _not_a_name(node: ast.AST) -> str:
    """Why ``node`` (a chain of `.` and `[...]`) is no dotted name."""
    while isinstance(node, ast.Attribute | ast.Subscript):
        if isinstance(node, ast.Subscript) and not (
            isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str)
        ):
            return 'a part in brackets is a quoted name: `arm["8"].position`'
        node = node.value
    return "attribute access is only allowed on names"


def _underscored(node: ast.AST) -> str | None:
    """The first unquoted part of a name that starts with an underscore (refused: a quoted part is a model's
    name, read as a whole like every dotted name, so it may)."""
    return next((part for part, quoted in _parts(node) or [] if not quoted and part.startswith("_")), None)


class _Compiler:
    def __init__(self, text: str) -> None:
        self.text = text
        self.names: set[str] = set()
        self.calls: set[str] = set()
        self.call_args: set[tuple[str, tuple[str, ...]]] = set()
        self.count = 0
        self.parts: dict[str, _Part] = {}

    def shown(self, node: ast.AST, fn: Evaluator, extremum_of: str | None = None) -> Evaluator:
        """Remember a sub-expression for explain() (by its text, once)."""
        text = ast.get_source_segment(self.text, node)
        if text and text not in self.parts:
            self.parts[text] = _Part(text, fn, extremum_of)
        return fn

    def fail(self, node: ast.AST, what: str) -> ExpressionError:
        col = getattr(node, "col_offset", None)
        where = f" at character {col + 1}" if col is not None else ""
        return ExpressionError(f"{what}{where} in expression {self.text!r}")

    def compile(self, node: ast.AST) -> Evaluator:  # noqa: C901 - one dispatch over the whitelist
        self.count += 1
        if self.count > MAX_NODES:
            raise self.fail(node, "expression too long")
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool | int | float | str):
                value = bounded(node.value)
                return lambda r: value
            raise self.fail(node, f"constant {node.value!r} not allowed")
        if isinstance(node, ast.Name | ast.Attribute | ast.Subscript):
            name = _dotted(node)
            if name is None:
                raise self.fail(node, _not_a_name(node))
            if _underscored(node) is not None:
                raise self.fail(node, f"name `{name}` not allowed (underscore)")
            if name in CONSTANTS:
                constant = CONSTANTS[name]
                return lambda r: constant
            self.names.add(name)
            return self.shown(node, lambda r: bounded(r.value(name)))
        if isinstance(node, ast.BinOp) and type(node.op) in _BIN:
            op, left, right = _BIN[type(node.op)], self.compile(node.left), self.compile(node.right)
            return self.shown(node, lambda r: op(left(r), right(r)))
        if isinstance(node, ast.UnaryOp):
            operand = self.compile(node.operand)
            if isinstance(node.op, ast.USub):
                return lambda r: -bounded(operand(r))
            if isinstance(node.op, ast.UAdd):
                return lambda r: +bounded(operand(r))
            if isinstance(node.op, ast.Not):
                return lambda r: not operand(r)
        if isinstance(node, ast.BoolOp):
            parts = [self.compile(v) for v in node.values]
            if isinstance(node.op, ast.And):
                return lambda r: all(p(r) for p in parts)
            return lambda r: any(p(r) for p in parts)
        if isinstance(node, ast.Compare) and all(type(o) in _CMP for o in node.ops):
            first = self.compile(node.left)
            rest = [(_CMP[type(o)], self.compile(c)) for o, c in zip(node.ops, node.comparators, strict=True)]

            def compare(r: Resolver) -> bool:
                left = first(r)
                for op, right_fn in rest:
                    right = right_fn(r)
                    if not op(left, right):
                        return False
                    left = right
                return True

            return compare
        if isinstance(node, ast.IfExp):
            test, body, orelse = self.compile(node.test), self.compile(node.body), self.compile(node.orelse)
            return lambda r: body(r) if test(r) else orelse(r)
        if isinstance(node, ast.Call):
            return self._call(node)
        raise self.fail(node, f"`{type(node).__name__}` is not allowed")

    def _call(self, node: ast.Call) -> Evaluator:
        if not isinstance(node.func, ast.Name) or node.keywords:
            raise self.fail(node, "only plain calls of known functions are allowed")
        fname = node.func.id
        if fname in PURE_FUNCTIONS:
            least, most, signature = ARITY[fname]
            if len(node.args) < least or (most is not None and len(node.args) > most):
                count = str(least) if least == most else f"{least} or more" if most is None else f"{least} to {most}"
                raise self.fail(
                    node, f"{fname}() takes {count} argument{'s' if most != 1 else ''} ({signature}), "
                    f"found {len(node.args)}",
                )
            args = [self.compile(a) for a in node.args]
            fn = _nan_on_math_error(PURE_FUNCTIONS[fname])
            group = _dotted(node.args[0]) if fname in ("max", "min") and len(node.args) == 1 else None
            return self.shown(node, lambda r: fn(*(a(r) for a in args)), group)
        if fname in RUNNER_FUNCTIONS:
            self.calls.add(fname)
            if len(node.args) != RUNNER_ARITY[fname]:
                raise self.fail(node, f"{fname}() takes {RUNNER_ARITY[fname]} argument(s), found {len(node.args)}")
            literal: list[str] = []
            for a in node.args:
                value = a.value if isinstance(a, ast.Constant) else _dotted(a)
                if not isinstance(value, str):
                    raise self.fail(node, f"{fname}() takes names or strings")
                if not isinstance(a, ast.Constant) and _underscored(a) is not None:
                    raise self.fail(a, f"name `{value}` not allowed (underscore)")
                literal.append(value)
            self.call_args.add((fname, tuple(literal)))
            return self.shown(node, lambda r: r.call(fname, literal))
        known = ", ".join(sorted([*PURE_FUNCTIONS, *RUNNER_FUNCTIONS]))
        raise self.fail(node, f"unknown function `{fname}` (known: {known})")


def compile_expression(text: str) -> Expression:
    """Parse and check ``text``; raise :class:`ExpressionError` if it is outside the grammar."""
    if not isinstance(text, str) or not text.strip():
        raise ExpressionError("expected an expression, found nothing")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression longer than {MAX_LENGTH} characters")
    source = text.strip()
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"syntax error at character {exc.offset or 0} in expression {text!r}") from None
    except (ValueError, RecursionError, MemoryError):
        raise ExpressionError(f"cannot parse expression {text!r}") from None
    compiler = _Compiler(source)
    try:
        fn = compiler.compile(tree.body)
    except RecursionError:
        raise ExpressionError(f"expression nested too deeply: {text!r}") from None
    whole = ast.get_source_segment(source, tree.body)
    return Expression(
        text=source,
        names=frozenset(compiler.names),
        calls=frozenset(compiler.calls),
        _fn=fn,
        call_args=frozenset(compiler.call_args),
        parts=tuple(p for t, p in compiler.parts.items() if t != whole),
    )
