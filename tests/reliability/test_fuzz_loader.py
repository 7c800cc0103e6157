"""Fuzzing the loader: every hostile document loads (and compiles) or is refused with located issues.

The requirement (issue 9): whatever a scenario file holds, ``load_scenario``/``load_all`` followed by
``build_program`` either succeeds, giving a compiled world an engine can be built from (finite poses,
positive finite masses and inertias, unit quaternions and axes, steps and bodies within the limits),
or raises :class:`ScenarioValidationError` whose every issue names the file, a line and a column
inside it, and a message: never another exception. ``FUZZ_CASES`` sets the number of cases (see
conftest.py); the CLI is checked on a few hostile files in a subprocess (exit 2, no traceback).
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from backends.types import Motion
from runner.compile.program import Program, build_program
from runner.errors import Issue, ScenarioValidationError
from runner.language.load import LoadedScenario, load_all, load_scenario, parse_overrides
from runner.language.refs import MAX_BODIES, MAX_STEPS

from .conftest import FUZZ_CASES, count, fuzz_settings
from .hostile import NUMBERS, ROOT, SEEDS, STRINGS, Case, documents, texts, walk

COMMAND_LINE = "<command line>"
_BREAKS = re.compile("\r\n|[\r\n\x85\u2028\u2029]")  # what YAML counts as a line break
DOTTED = sorted({".".join(map(str, p)) for s in SEEDS if s.data is not None for p in walk(s.data) if p})
override_items = st.builds(
    lambda key, value: f"{key}={value}",
    st.one_of(st.sampled_from(DOTTED), texts),
    st.one_of(st.sampled_from([repr(n) for n in NUMBERS] + STRINGS), texts),
)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A scenario folder with the repository's sounds, so that sound references can resolve."""
    path = tmp_path_factory.mktemp("fuzz")
    shutil.copytree(ROOT / "scenarios" / "sounds", path / "sounds")
    return path


def line_count(data: bytes) -> int:
    try:
        return len(_BREAKS.findall(data.decode("utf-8"))) + 1
    except UnicodeDecodeError:
        return data.count(b"\n") + 1


def assert_located(exc: ScenarioValidationError, path: Path, lines: int) -> None:
    assert exc.issues, "a refusal without issues"
    for issue in exc.issues:
        assert isinstance(issue, Issue)
        assert issue.message.strip(), issue
        if issue.file == COMMAND_LINE:
            continue  # a --set item: it has no line
        assert issue.file == str(path), issue
        assert 1 <= issue.line <= lines and issue.column >= 1, f"issue not located in the file ({lines} lines): {issue}"
    assert str(exc)


def _finite(*values: object) -> bool:
    return bool(np.isfinite(np.asarray(values, dtype=float)).all())


PHYSICAL = ("world", "surface", "surfaces", "bodies", "joints", "collisions", "intervals", "on", "inputs")


def assert_finite_model(loaded: LoadedScenario) -> None:
    """Every number of the physical sections of a validated scenario is finite (a friction `mu` may be inf)."""
    dumped = loaded.model.model_dump(by_alias=True)
    for section in PHYSICAL:
        for path in walk(dumped.get(section)):
            value = dumped[section]
            for part in path:
                value = value[part]
            if isinstance(value, float) and path[-1:] != ("mu",):
                assert math.isfinite(value), f"{section}.{'.'.join(map(str, path))} = {value} was accepted"


def unit(v: tuple[float, ...]) -> bool:
    return _finite(*v) and abs(math.hypot(*v) - 1.0) < 1e-9


def assert_sane(program: Program) -> None:
    """What an engine may assume of a compiled world (backends/types.py)."""
    world = program.world
    assert 1 <= program.steps <= MAX_STEPS, f"{program.steps} steps"
    assert 1 <= len(world.bodies) <= MAX_BODIES, f"{len(world.bodies)} bodies"
    assert _finite(*world.gravity, world.dt, world.duration) and world.dt > 0 and world.substeps >= 1, world
    for b in world.bodies:
        where = f"body `{b.name}`"
        assert _finite(*b.pos, *b.lin_vel, *b.ang_vel), f"{where}: pos {b.pos}, vel {b.lin_vel}, {b.ang_vel}"
        assert _finite(*b.shape.size, b.shape.radius, b.shape.length), f"{where}: {b.shape}"
        assert unit(b.quat), f"{where}: quat {b.quat}"
        if b.motion is Motion.DYNAMIC:
            ok = _finite(b.mass, *b.inertia) and b.mass > 0 and min(b.inertia) > 0
            assert ok, f"{where}: mass {b.mass}, inertia {b.inertia}"
    for j in world.joints:
        assert unit(j.axis) and _finite(*j.anchor), f"joint `{j.name}`: axis {j.axis}, anchor {j.anchor}"
        if j.axis2 is not None:
            cross = np.cross(j.axis, j.axis2)
            assert unit(j.axis2) and np.linalg.norm(cross) > 1e-6, f"joint `{j.name}`: axes {j.axis}, {j.axis2}"


def cases_for(path: Path, case: Case, pick: int, overrides: tuple) -> list[LoadedScenario]:  # noqa: ANN001
    if pick % 10 == 0:
        return load_all(path, None, True, overrides)
    if pick % 10 == 1:
        return [load_scenario(path, "no-such-variant", overrides)]
    if case.variants and pick % 2:
        return [load_scenario(path, case.variants[pick % len(case.variants)], overrides)]
    return [load_scenario(path, None, overrides)]


def check_document(path: Path, case: Case, pick: int, items: list[str]) -> str:
    """Load ``case`` (one variant, a wrong one, or all) and compile it; return the outcome."""
    path.write_bytes(case.data)
    try:
        overrides = parse_overrides(items)
        loaded = cases_for(path, case, pick, overrides)
    except ScenarioValidationError as exc:
        assert_located(exc, path, line_count(case.data))
        return "refused"
    for one in loaded:
        assert_finite_model(one)
        try:
            program = build_program(one)
        except ScenarioValidationError as exc:  # `scenario validate` and `run` compile too: same contract
            assert_located(exc, path, line_count(case.data))
            return "refused when compiled"
        assert_sane(program)
    return "loaded"


@fuzz_settings(FUZZ_CASES)
@given(case=documents(), pick=st.integers(0, 99), items=st.lists(override_items, max_size=2) | st.just([]))
def test_every_document_loads_or_is_refused_with_located_issues(
    folder: Path, case: Case, pick: int, items: list[str]
) -> None:
    outcome = check_document(folder / "case.yaml", case, pick, items)
    count("loader fuzzing", outcome)


# ---- the same through the command line ----------------------------------------------------------

SMALL = """\
schema_version: 1
scenario: t
world: {dt: 0.04, duration: 1}
bodies:
  box: {box: [0.3, 0.3, 0.3], density: 500, pos: [0, 0, 1]}
"""
HOSTILE_FILES: dict[str, bytes] = {
    "python tag": (SMALL + "x: !!python/object/apply:os.system ['touch pwned']\n").encode(),
    "alias bomb": (
        SMALL
        + "a: &a [1,1,1,1,1,1,1,1,1,1]\nb: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a]\nc: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b]\n"
        + "d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c]\ne: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]\nf: [*e,*e,*e,*e,*e,*e]\n"
    ).encode(),
    "deep nesting": (SMALL + "x: " + "[" * 3000 + "]" * 3000 + "\n").encode(),
    "control character": (SMALL + 'description: "bell \x07"\n').encode(),
    "5000-digit number": SMALL.replace("density: 500", "density: " + "9" * 5000).encode(),
    "not UTF-8": SMALL.encode() + b"description: caf\xe9\n",
    "random bytes": bytes(range(256)) * 4,
    "expression escape": (SMALL + 'assertions:\n  - {name: a, always: "().__class__.__bases__"}\n').encode(),
}


@pytest.mark.parametrize("name", list(HOSTILE_FILES))
def test_validate_refuses_hostile_files_with_exit_2_and_no_traceback(tmp_path: Path, name: str) -> None:
    path = tmp_path / "hostile.yaml"
    path.write_bytes(HOSTILE_FILES[name])
    done = subprocess.run(
        [sys.executable, "-m", "runner", "validate", str(path)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert errors, done.stderr
    for line in errors:
        assert re.match(rf"error: {re.escape(str(path))}:[1-9]\d*:[1-9]\d*: \S", line), line
    assert not (tmp_path / "pwned").exists()
