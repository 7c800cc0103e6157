"""`<body>.energy` (runner.sim.resolver): a body's mechanical energy, judged against an independent sum.

The expected value is computed another way than the resolver's: scipy's Rotation (scalar-last
quaternions) turns the centre of mass and the inertia tensor into the world frame, and the rotational
energy is 1/2 w^T (R I_body R^T) w with w in the world frame (the resolver turns w into the body frame
instead). Both are float64 sums of a few dozen terms of size <= 50 J: they agree to 1e-12 relative.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from backends.types import BodySpec, BodyStates, CompiledWorld, Motion, Shape, ShapeKind
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.sim.resolver import Snapshot, StateResolver

GRAVITY = (0.3, -0.2, -9.81)


def body(name: str, com: tuple[float, float, float], inertia_quat: tuple[float, float, float, float]) -> BodySpec:
    return BodySpec(
        name=name,
        motion=Motion.DYNAMIC,
        shape=Shape(ShapeKind.BOX, (0.1, 0.2, 0.3)),
        mass=2.5,
        inertia=(0.04, 0.03, 0.02),
        pos=(0.0, 0.0, 0.0),
        quat=(1.0, 0.0, 0.0, 0.0),
        com=com,
        inertia_quat=inertia_quat,
    )


def expected(spec: BodySpec, pos: np.ndarray, quat: np.ndarray, v: np.ndarray, w: np.ndarray) -> float:
    rot = Rotation.from_quat([quat[1], quat[2], quat[3], quat[0]]).as_matrix()
    axes = Rotation.from_quat([*spec.inertia_quat[1:], spec.inertia_quat[0]]).as_matrix()
    tensor_world = rot @ axes @ np.diag(spec.inertia) @ axes.T @ rot.T
    arm = rot @ np.asarray(spec.com)
    v_com = v + np.cross(w, arm)
    return float(
        0.5 * spec.mass * v_com @ v_com + 0.5 * w @ tensor_world @ w - spec.mass * (pos + arm) @ np.asarray(GRAVITY)
    )


def test_energy_of_a_body_with_a_com_offset_and_turned_principal_axes_and_of_a_group() -> None:
    q = np.array([0.9, 0.1, -0.3, 0.2])
    specs = (
        body("plain", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)),
        body("link", (0.05, -0.02, 0.1), tuple((q / np.linalg.norm(q)).tolist())),  # type: ignore[arg-type]
    )
    world = CompiledWorld("t", GRAVITY, 0.01, 1, 1.0, specs)
    rng = np.random.default_rng(17)
    quats = rng.normal(size=(2, 4))
    rows = np.hstack([rng.normal(size=(2, 3)), quats / np.linalg.norm(quats, axis=1)[:, None], rng.normal(size=(2, 6))])
    snap = Snapshot()
    snap.bodies = BodyStates.from_rows(rows)
    resolver = StateResolver(world, {"both": ["plain", "link"]}, {}, {}, snap, {}, eps=2.0**-52)
    want = [expected(s, rows[i, 0:3], rows[i, 3:7], rows[i, 7:10], rows[i, 10:13]) for i, s in enumerate(specs)]
    assert resolver.value("plain.energy") == pytest.approx(want[0], rel=1e-12)
    assert resolver.value("link.energy") == pytest.approx(want[1], rel=1e-12)
    assert resolver.value("both.energy") == pytest.approx(want, rel=1e-12)
    # the getter reads the snapshot's current state, not the one it was built on
    snap.bodies = BodyStates.from_rows(rows[::-1].copy())
    assert resolver.value("link.energy") == pytest.approx(
        expected(specs[1], rows[0, 0:3], rows[0, 3:7], rows[0, 7:10], rows[0, 10:13]), rel=1e-12
    )


SCENARIO = """\
schema_version: 1
scenario: e
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}}
bodies:
  box: {{box: [0.1, 0.2, 0.3], mass: 1, pos: [0, 0, 1]}}
assertions:
  - {{name: e, at: end, value: {name}, near: 0, tol: 1}}
"""


def test_energy_is_a_readable_name_and_a_misspelling_is_refused_with_a_suggestion(tmp_path: Path) -> None:
    path = tmp_path / "e.yaml"
    path.write_text(SCENARIO.format(name="box.energy"))
    load_scenario(path)
    path.write_text(SCENARIO.format(name="box.enrgy"))
    with pytest.raises(ScenarioValidationError, match=r"unknown name `box.enrgy`.*did you mean `box.energy`"):
        load_scenario(path)
