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
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from runner.language.explain import fmt, group_member
from runner.language.expression_values import (
    ARITY,
    BINARY_OPERATORS,
    COMPARISONS,
    CONSTANTS,
    PURE_FUNCTIONS,
    RUNNER_ARITY,
    RUNNER_FUNCTIONS,
    EvaluationError,
    ExpressionError,
    bounded,
    is_number,
    kind_of,
    nan_on_math_error,
)

# the errors (runner.language.expression_values) and fmt (runner.language.explain) are re-exported: the
# language, the compiler and the run import them from here
__all__ = ["EvaluationError", "Expression", "ExpressionError", "Resolver", "compile_expression", "fmt"]

MAX_LENGTH = 2000
MAX_NODES = 500


class Resolver(Protocol):
    def value(self, name: str) -> Any: ...  # a dotted name, e.g. "box.pos.z"
    def call(self, func: str, args: Sequence[Any]) -> Any: ...  # runner-level functions (contact, playing...)


@dataclass(frozen=True)
class _Part:
    """A sub-expression shown when a condition fails: its text and how to evaluate it."""

    text: str
    fn: Callable[[Resolver], Any]
    extremum_of: str | None = None  # `max(crate.speed)`: the group's dotted name, to name the member


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
        if not is_number(value):
            raise EvaluationError(f"cannot evaluate {self.text!r}: expected true or false, found {kind_of(value)}")
        return bool(value) and not (isinstance(value, float) and math.isnan(value))

    def number(self, resolver: Resolver) -> float:
        value = self.evaluate(resolver)
        if not is_number(value):
            raise EvaluationError(f"cannot evaluate {self.text!r}: expected a number, found {kind_of(value)}")
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
        if isinstance(node, ast.BinOp) and type(node.op) in BINARY_OPERATORS:
            op, left, right = BINARY_OPERATORS[type(node.op)], self.compile(node.left), self.compile(node.right)
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
        if isinstance(node, ast.Compare) and all(type(o) in COMPARISONS for o in node.ops):
            first = self.compile(node.left)
            rest = [(COMPARISONS[type(o)], self.compile(c)) for o, c in zip(node.ops, node.comparators, strict=True)]

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
                    node,
                    f"{fname}() takes {count} argument{'s' if most != 1 else ''} ({signature}), found {len(node.args)}",
                )
            args = [self.compile(a) for a in node.args]
            fn = nan_on_math_error(PURE_FUNCTIONS[fname])
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
