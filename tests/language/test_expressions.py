"""The expression grammar: what it computes, and everything it refuses."""

from __future__ import annotations

import math

import pytest

from runner.language.expressions import ExpressionError, compile_expression


class Values:
    def __init__(self, **values: object) -> None:
        self.values = {k.replace("__", "."): v for k, v in values.items()}
        self.calls: list[tuple[str, list[object]]] = []

    def value(self, name: str) -> object:
        return self.values[name]

    def call(self, func: str, args: list[object]) -> object:
        self.calls.append((func, list(args)))
        return True


@pytest.mark.parametrize(
    "text,expected",
    [
        ("1 + 2*3", 7),
        ("2**10", 1024.0),
        ("7 // 2 + 7 % 2", 4),
        ("-box__pos__z", -1.5),
        ("abs(-2.5)", 2.5),
        ("sqrt(16) + hypot(3, 4)", 9.0),
        ("min(3, 1, 2)", 1),
        ("max(box__pos__z, 2)", 2),
        ("1 < box__pos__z < 2", True),
        ("box__pos__z > 2 or state__open", True),
        ("not state__open", False),
        ("3 if state__open else 4", 3),
        ("round(radians(180), 6)", round(math.pi, 6)),
        ("clamp(5, 0, 1)", 1),
        ("mean(group__z)", 2.0),
        ("max(group__z) - min(group__z)", 2.0),
        ("len(group__z)", 3),
        ("1 == 1.0 != 2", True),
        ("true and not false", True),
    ],
)
def test_values(text: str, expected: object) -> None:
    r = Values(box__pos__z=1.5, state__open=True, group__z=[1.0, 2.0, 3.0])
    assert compile_expression(text.replace("__", ".")).evaluate(r) == expected


def test_names_are_collected_and_runner_functions_called_with_literal_names() -> None:
    expr = compile_expression("contact(box, door) and box.pos.z > 0.1 and playing('drop-box')")
    assert expr.names == frozenset({"box.pos.z"})
    assert expr.calls == frozenset({"contact", "playing"})
    r = Values(box__pos__z=1.0)
    assert expr.evaluate(r) is True
    assert r.calls == [("contact", ["box", "door"]), ("playing", ["drop-box"])]


def test_division_by_zero_gives_nan_not_a_crash() -> None:
    assert math.isnan(compile_expression("1/0").evaluate(Values()))


@pytest.mark.parametrize(
    "text,expected",
    [
        # floor() of a float is an integer; their product would be a 2,046-bit integer (and squaring it each
        # step, gigabytes): an integer beyond 2**53 becomes a float, beyond the float range +-inf, as
        # float arithmetic gives for 1e308*1e308.
        ("floor(1e308)*floor(1e308)", math.inf),
        ("-floor(1e308)*floor(1e308)", -math.inf),
        ("floor(1e308)*floor(1e308) - floor(1e308)*floor(1e308)", None),  # inf - inf: NaN
        ("1" + "0" * 400, math.inf),  # a literal beyond the float range
        ("round(1e300) * 10", 1e301),
        ("sum(big, big)", math.inf),
        ("big + 1", math.inf),
        ("2**53 + 1", 2.0**53),  # beyond 2**53: a float (9007199254740993 is not one)
        ("2**10", 1024.0),
        ("floor(2.5) * 3", 6),  # small integers stay exact
        # a negative base with a fractional power is NaN, never a complex number (docs/language.md)
        ("(box__pos__z - 2)**0.5", None),
        ("(-8)**(1/3)", None),
        ("9**9**9", None),  # an overflow: NaN, as exp(1000)
        ("0**-1", None),
        ("0.5**100", 0.5**100),  # an exponent beyond 64 is a power like any other
    ],
)
def test_integers_are_bounded_and_math_errors_give_nan(text: str, expected: float | None) -> None:
    value = compile_expression(text.replace("__", ".")).evaluate(Values(box__pos__z=1.5, big=10**400))
    assert isinstance(value, int | float) and not isinstance(value, complex)
    if expected is None:
        assert math.isnan(value)
    else:
        assert value == expected
    assert not isinstance(value, int) or abs(value) <= 2**53


@pytest.mark.parametrize(
    "text,message",
    [
        ("__import__('os').system('true')", "only plain calls"),
        ("__import__('os')", "unknown function `__import__`"),
        ("box.__class__", "underscore"),
        ("box._private", "underscore"),
        ("(1).real", "attribute access is only allowed on names"),
        ("().__class__.__bases__", "attribute access is only allowed on names"),
        ("open('/etc/passwd')", "unknown function `open`"),
        ("eval('1')", "unknown function `eval`"),
        ("exec('x=1')", "unknown function `exec`"),
        ("getattr(box, 'pos')", "unknown function `getattr`"),
        ("max.__call__(1)", "only plain calls"),
        ("[1, 2]", "`List` is not allowed"),
        ("{1: 2}", "`Dict` is not allowed"),
        ("lambda: 1", "`Lambda` is not allowed"),
        ("x[0]", "a part in brackets is a quoted name"),
        ("(1)[\"a\"]", "attribute access is only allowed on names"),
        ("f'{x}'", "`JoinedStr` is not allowed"),
        ("[c for c in 'ab']", "`ListComp` is not allowed"),
        ("(x := 1)", "`NamedExpr` is not allowed"),
        ("abs(x=1)", "only plain calls"),
        ("1 +", "syntax error"),
        ("import os", "syntax error"),
        ("", "expected an expression"),
        ("1" * 3000, "longer than"),
    ],
)
def test_refused(text: str, message: str) -> None:
    with pytest.raises(ExpressionError) as info:
        compile_expression(text).evaluate(Values(x=1, box=1))
    assert message in str(info.value)
