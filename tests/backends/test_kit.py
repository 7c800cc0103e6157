"""The backend kit (backends/_kit) on its own: options, the kinematic track, forces, substep means, contact
grouping and the merge of engine steps. No engine is needed; the contract suite runs it on every engine."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from dataclasses import dataclass

import numpy as np
import pytest

from backends._kit import (
    BackendOptions,
    KinematicTrack,
    OneStepForces,
    SubstepContacts,
    SubstepMean,
    group_by_pair,
    merge_substeps,
    option,
    substep_times,
)
from backends.errors import UnsupportedFeature
from backends.geometry import integrate_quat
from backends.registry import (
    check_capabilities,
    check_options,
    engine_modules,
    get_backend,
    is_installed,
    list_backends,
    options_of,
)
from backends.testing import worlds as w
from backends.types import Contact, JointKind, JointSpec, Motion

# --- options ---------------------------------------------------------------------------------------------


def _even(value: object) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value % 2:
        raise ValueError("an even integer")
    return value


@dataclass(frozen=True)
class Sample(BackendOptions):
    count: int = option(3, "how many", minimum=1)
    share: float = option(0.5, "a fraction", minimum=0.0, min_exclusive=True, maximum=1.0)
    mode: str = option("a", "a or b", choices=("a", "b"))
    flag: bool = option(True, "on or off")
    limit: float | None = option(None, "optional, positive", minimum=0.0, min_exclusive=True)
    pair: int = option(2, "even", convert=_even)


def test_options_defaults_and_values() -> None:
    assert Sample.parse({}, "x") == Sample()
    got = Sample.parse({"count": 7, "share": 1, "mode": "b", "flag": False, "limit": 2, "pair": 4}, "x")
    assert got == Sample(7, 1.0, "b", False, 2.0, 4)
    assert isinstance(got.share, float) and isinstance(got.limit, float)
    assert Sample.parse({"limit": None, "count": 2.0}, "x").count == 2  # a whole float is an integer
    assert list(Sample.keys()) == ["count", "share", "mode", "flag", "limit", "pair"]


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        ({"cont": 1}, r"Unknown option\(s\) cont in backend_options.x. Accepted: count, flag, limit, mode, pair, "),
        ({"count": 0}, r"Invalid `backend_options.x.count`. Expected an integer, 1 <= count. Received: count=0."),
        ({"count": 1.5}, r"Expected an integer, 1 <= count. Received: count=1.5."),
        ({"count": True}, r"Expected an integer, 1 <= count. Received: count=True."),
        ({"share": 0.0}, r"Expected a number, 0 < share <= 1. Received: share=0.0."),
        ({"share": math.inf}, r"Expected a number, 0 < share <= 1."),
        ({"share": "half"}, r"Expected a number, 0 < share <= 1. Received: share='half'."),
        ({"mode": "c"}, r"Expected one of a, b. Received: mode='c'."),
        ({"flag": "yes"}, r"Expected true or false. Received: flag='yes'."),
        ({"limit": -1}, r"Expected a number, 0 < limit. Received: limit=-1."),
        ({"pair": 3}, r"Expected an even integer. Received: pair=3."),
    ],
)
def test_bad_options_name_key_expectation_and_value(raw: dict[str, object], message: str) -> None:
    with pytest.raises(UnsupportedFeature, match=message):
        Sample.parse(raw, "x")


def test_every_backend_checks_its_options_before_anything_is_built() -> None:
    for entry in list_backends(include_hidden=True):
        try:
            cls = get_backend(entry.name)
        except Exception:  # noqa: BLE001 - an engine not installed: nothing of it to check
            continue
        world = w.world("opts", [w.box("box", w.LAB_BOX, (0.0, 0.0, 1.0))])
        bad = type(world)(**{**world.__dict__, "backend_options": {entry.name: {"no_such_key": 1}}})
        unknown = f"Unknown option\\(s\\) no_such_key in backend_options.{entry.name}"
        with pytest.raises(UnsupportedFeature, match=unknown):
            check_capabilities(cls, bad)


# --- motion ----------------------------------------------------------------------------------------------


def test_kinematic_track_moves_each_body_along_its_velocity() -> None:
    world = w.kinematic_platform()
    track = KinematicTrack(world)
    assert 0 in track and 1 not in track and [i for i, _ in track.items()] == [0]
    q = (math.cos(0.15), math.sin(0.15), 0.0, 0.0)
    pose = track.set(0, (1, 2, 3), q, (0.5, 0.0, -1.0), (0.0, 0.0, 2.0))
    assert pose.pos == (1.0, 2.0, 3.0) and all(isinstance(c, float) for c in pose.pos)
    pos, quat = pose.at(0.25)
    assert pos == (1.125, 2.0, 2.75) and quat == integrate_quat(q, (0.0, 0.0, 2.0), 0.25)
    track.advance(0.5)  # not set again: it keeps its velocity
    assert track[0].pos == (1.25, 2.0, 2.5) and track[0].lin_vel == (0.5, 0.0, -1.0)
    assert track[0].quat == integrate_quat(q, (0.0, 0.0, 2.0), 0.5)


def test_one_step_forces_accumulate_per_body() -> None:
    forces = OneStepForces()
    assert not forces
    forces.add(2, (1.0, 0.0, 0.0), (0.0, 0.0, 0.5))
    forces.add(0, (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
    forces.add(2, (1.0, 0.0, 0.0), (0.0, 0.0, 0.5))
    assert [(i, acc.tolist()) for i, acc in forces.items()] == [(2, [2.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
                                                                 (0, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0])]  # fmt: skip
    forces.clear()
    assert not forces


def test_substep_mean_and_times() -> None:
    mean = SubstepMean(2)
    assert mean.mean.tolist() == [0.0, 0.0]
    mean.start()
    for values in ([100.0, -1.0], [60.0, -1.0], [0.0, -1.0], [0.0, -1.0]):
        mean.add(values)
    assert mean.finish().tolist() == [40.0, -1.0] and mean.mean.tolist() == [40.0, -1.0]
    assert substep_times(0.04, 1) == [0.04]
    assert substep_times(0.04, 4) == [0.04 * 0.25, 0.04 * 0.5, 0.04 * 0.75, 0.04]


# --- contacts --------------------------------------------------------------------------------------------


def test_points_grouped_per_pair_in_engine_order() -> None:
    first = np.array([3, 0, 1, 3, 1])
    second = np.array([1, 2, 3, 1, 3])  # pair (1, 3) in both orders, (0, 2) once
    depth = np.array([0.001, -0.0, 0.003, 0.002, 0.0])
    force = np.array([0.1, 5.0, 0.2, 0.3, 1e-17])
    got = group_by_pair(4, first, second, depth, force)
    assert got == [Contact(0, 2, 1, 0.0, 5.0), Contact(1, 3, 4, 0.003, ((0.1 + 0.2) + 0.3) + 1e-17)]
    assert math.copysign(1.0, got[0].depth) == 1.0  # no -0.0 depth
    assert group_by_pair(4, np.array([]), np.array([]), np.array([]), np.array([])) == []
    nan = group_by_pair(2, np.array([0, 0]), np.array([1, 1]), np.array([math.nan, 0.002]), np.array([math.nan] * 2))
    assert nan[0][:4] == (0, 1, 2, 0.002) and math.isnan(nan[0].normal_force)


def test_engine_steps_merged_into_the_scenario_step() -> None:
    a = [Contact(0, 1, 4, 0.002, 10.0), Contact(1, 2, 1, 0.001, 4.0)]
    b = [Contact(0, 1, 2, 0.003, 6.0)]
    assert merge_substeps([a], 1) == a and merge_substeps([a], 1) is not a
    merged = merge_substeps([a, b, [], []], 4)
    assert merged == [Contact(0, 1, 4, 0.003, 4.0), Contact(1, 2, 1, 0.001, 1.0)]  # most, deepest, mean of 4
    steps = SubstepContacts(3)
    steps.start()
    steps.add(a)
    steps.add([])
    assert steps.merged(b) == [Contact(0, 1, 4, 0.003, 16.0 / 3), Contact(1, 2, 1, 0.001, 4.0 / 3)]
    steps.start()
    assert steps.merged() == []


def test_the_registry_checks_options_without_the_engine() -> None:
    """``check_options`` (for ``validate``) uses the very class the adapter parses with, engine-free."""
    for entry in list_backends(include_hidden=True):
        assert check_options(entry.name, {}) == options_of(entry.name)()
        if is_installed(entry.name):
            assert get_backend(entry.name).Options is options_of(entry.name)
    with pytest.raises(UnsupportedFeature, match=r"Invalid `backend_options.ode.cfm`. Expected a number, 1e-08 <= cfm"):
        check_options("ode", {"cfm": 1e-10})
    code = "import sys\nfrom backends.registry import check_options\n" + "".join(
        f"check_options({e.name!r}, {{}})\n" for e in list_backends(include_hidden=True)
    ) + f"print(sorted(set({sorted(engine_modules())!r}) & set(sys.modules)))\n"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_python_and_numpy_grouping_give_the_same_numbers() -> None:
    """Few points are grouped in a Python loop, many with numpy: the same counts, depths and sums, bit for bit."""
    from backends._kit import contacts as kit

    def same(x: list[Contact], y: list[Contact]) -> bool:
        return len(x) == len(y) and all(
            a[:4] == b[:4] and math.copysign(1.0, a.depth) == math.copysign(1.0, b.depth) == 1.0
            and (
                (a.normal_force == b.normal_force
                 and math.copysign(1.0, a.normal_force) == math.copysign(1.0, b.normal_force))
                or (math.isnan(a.normal_force) and math.isnan(b.normal_force))
            )
            for a, b in zip(x, y, strict=True)
        )

    rng = np.random.default_rng(7)
    for size, listed_by_pair in [(n, False) for n in (1, 5, kit.NUMPY_FROM - 1, kit.NUMPY_FROM, 300)] + [
        (n, True) for n in (kit.NUMPY_FROM, 300)  # points already pair by pair (MuJoCo's order): no sort
    ]:
        first, second = rng.integers(0, 6, size), rng.integers(0, 6, size)
        if listed_by_pair:
            order = np.argsort(np.minimum(first, second) * 6 + np.maximum(first, second), kind="stable")
            first, second = first[order], second[order]
        depth = np.where(rng.random(size) < 0.2, -0.0, rng.random(size) * 1e-3)
        force = rng.random(size) * 100.0
        force[rng.random(size) < 0.1] = math.nan if size % 2 else 0.0
        force[rng.random(size) < 0.1] = -0.0  # a pair of -0.0 forces sums to -0.0, with 0.0 to 0.0
        force[rng.random(size) < 0.02] = math.inf
        python = kit._grouped_in_python(6, first.tolist(), second.tolist(), depth.tolist(), force.tolist())
        numpy = kit._grouped_with_numpy(6, first, second, depth, force)
        assert same(python, numpy), size
        assert same(group_by_pair(6, first, second, depth, force), python), size


def test_the_pairs_that_can_touch() -> None:
    """backends._kit.pairs: a pair touches when one body is dynamic, no joint joins the two directly and the
    world does not exclude it; static and kinematic bodies never touch each other."""
    from backends._kit.pairs import touching_pairs

    bodies = [
        w.ground(),
        w.box("platform", (1.0, 1.0, 0.1), (0.0, 0.0, 0.5), motion=Motion.KINEMATIC),
        w.box("a", (0.1,) * 3, (0.0, 0.0, 1.0)),
        w.box("b", (0.1,) * 3, (0.0, 0.0, 2.0)),
        w.box("c", (0.1,) * 3, (0.0, 0.0, 3.0)),
    ]
    hinge = JointSpec("h", JointKind.HINGE, "b", "a", axis=(0.0, 1.0, 0.0), anchor=(0.0, 0.0, 1.5))
    world = dataclasses.replace(w.world("pairs", bodies, joints=(hinge,)), excluded_pairs=(("c", "ground"),))
    assert touching_pairs(world) == [(0, 2), (0, 3), (1, 2), (1, 3), (1, 4), (2, 4), (3, 4)]


def test_a_blend_combines_two_coefficients() -> None:
    from backends._kit.surfaces import Blend, solve_exact

    assert Blend.PRODUCT.combine(0.5, 0.4) == 0.2 and Blend.MIN.combine(0.5, 0.4) == 0.4
    target = {(0, 1): 0.25, (0, 2): 0.5}
    for blend in Blend:
        per_body = solve_exact(blend, 3, target, ["x", "y", "z"], "test")
        assert {p: blend.combine(per_body[p[0]], per_body[p[1]]) for p in target} == pytest.approx(target, rel=1e-12)


def test_a_deviation_names_a_test_that_exists_and_marks_only_its_case() -> None:
    """Every ``DEVIATIONS`` line names a test function of the shipped suite or of tests/ (a renamed test
    must not leave its line behind, unapplied), and a ``test[params]`` line marks that case alone."""
    import ast
    from pathlib import Path

    from backends.testing.tolerances import DEVIATIONS, deviation

    root = Path(__file__).resolve().parents[2]
    names: set[str] = set()
    for path in [*(root / "backends" / "testing").glob("*.py"), *(root / "tests").rglob("test_*.py")]:
        tree = ast.parse(path.read_text())
        names |= {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name.startswith("test_")}
    for test, _ in DEVIATIONS:
        assert test.partition("[")[0] in names, test
    assert deviation("test_resting_height", "sphere", "drake") is not None
    assert deviation("test_resting_height", "box", "drake") is None
    assert deviation("test_contact_resting", "", "drake") is not None
    assert deviation("test_contact_resting", "", "mujoco") is None
