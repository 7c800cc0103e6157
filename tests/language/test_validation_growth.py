"""Validation is linear in the file (issue 31): 20 nested `parallel:` with one invalid step took over
100 s (x2.2 per level: the error's location was read in 2**len(loc) ways), and 5,000 variants 126 s (each
variant's load checked every variant). The work is counted as Python function calls (deterministic, unlike
wall time on a shared machine) for a size n and 2n: linear work doubles, exponential or quadratic work
does not fit under the bounds below."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_all, load_scenario

HEAD = """\
schema_version: 1
scenario: grow
world: {dt: 0.04, duration: 0.2}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
"""


def calls(work: Callable[[], Any]) -> int:
    """How many Python functions ``work`` calls (C functions too)."""
    count = 0

    def profile(frame: Any, event: str, arg: Any) -> None:
        nonlocal count
        if event in ("call", "c_call"):
            count += 1

    sys.setprofile(profile)
    try:
        work()
    finally:
        sys.setprofile(None)
    return count


def nested(depth: int, leaf: str) -> str:
    step = leaf
    for _ in range(depth):
        step = "{parallel: [" + step + "]}"
    return HEAD + f"intervals:\n  deep: {step}\n"


@pytest.mark.parametrize("leaf", ["{wait: -1}", "{sound: {sound: 5}}", "{foo: 1}", "{func: [{bad: 1}]}"])
def test_an_error_deep_in_nested_intervals_is_located_in_linear_work(tmp_path: Path, leaf: str) -> None:
    def validate(depth: int) -> Callable[[], None]:
        path = tmp_path / f"deep{depth}.yaml"
        path.write_text(nested(depth, leaf))

        def work() -> None:
            with pytest.raises(ScenarioValidationError) as info:
                load_scenario(path)
            issues = info.value.issues
            assert all(issue.line == 7 and "intervals.deep.parallel[0]" in issue.path for issue in issues), issues

        return work

    validate(2)()  # warm the caches (pydantic's, the parse cache) before counting
    small, large = calls(validate(10)), calls(validate(20))
    # 10 more levels: the location has ~30 more parts; its reading is quadratic in the depth at most
    # (parts x nodes), so at most 4x; the 2**parts readings gave x2.2 per level (x2,600 here).
    assert large < 4 * small, (small, large)


def many_variants(n: int) -> str:
    lines = "".join(f"  v{i}: {{set: {{world.duration: 0.{i % 9 + 1}}}, inputs: [{{at: 0, event: e{i}}}]}}\n"
                    for i in range(n))  # fmt: skip
    return HEAD + "on: {e0: [{log: {message: hi}}]}\nvariants:\n" + lines


def test_every_variant_is_checked_once(tmp_path: Path) -> None:
    def load_every(n: int) -> Callable[[], None]:
        path = tmp_path / f"many{n}.yaml"
        path.write_text(many_variants(n))
        return lambda: load_all(path, None, all_variants=True)

    load_every(5)()
    small, large = calls(load_every(200)), calls(load_every(400))
    # linear: 2x; each load checking every variant (or copying, substituting, validating them all): ~4x
    assert large < 2.6 * small, (small, large)


def test_an_error_in_another_variant_is_reported_whichever_is_loaded(tmp_path: Path) -> None:
    """The `variants` section is checked once per file, and its problems still refuse every case of it."""
    path = tmp_path / "v.yaml"
    path.write_text(HEAD + "variants:\n  good: {set: {world.duration: 0.1}}\n  bad: {set: {}, inputs: 3}\n")
    for variant in (None, "good", "bad"):
        with pytest.raises(ScenarioValidationError) as info:
            load_scenario(path, variant)
        found = [f"{i.line}:{i.path}" for i in info.value.issues]
        assert found == ["8:variants.bad.inputs"] if variant != "bad" else ["8:inputs", "8:variants.bad.inputs"]


def test_a_set_into_the_variants_section_is_applied_before_the_variant(tmp_path: Path) -> None:
    """`--set variants.x...` edits the section (a copy: the parse cache's is shared by every load), and a
    file without variants refuses it naming the argument (it raised KeyError once, found by the fuzzer)."""
    path = tmp_path / "v.yaml"
    path.write_text(HEAD)
    with pytest.raises(ScenarioValidationError, match="unknown variant `x`"):
        load_scenario(path, None, (("variants.x.set", {}),))
    path.write_text(HEAD + "variants:\n  x: {set: {world.duration: 0.1}}\n")
    edited = load_scenario(path, "x", (("variants.x.set", {"world.duration": 0.12}),))
    assert edited.model.world.duration == 0.12
    assert load_scenario(path, "x").model.world.duration == 0.1  # the cached section was not changed
