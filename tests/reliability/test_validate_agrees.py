"""`scenario validate --backend X` refuses exactly what `scenario run --backend X` refuses before its first step
(issue 31): the engines' limits judged from the world (the tallest column each holds, DART's friction cone,
the joint trees PyBullet, MuJoCo and DART build) run with the capability check (``Backend.check_world``), so
both commands exit 2 with the same message.

Measured before: `box_pile --set params.count=50` validated (exit 0) and then `run` refused it on PyBullet
and ODE; a 3,000-link chain validated, and `run` on PyBullet built it for over 5 minutes before refusing the
column its links make (now refused before anything is built: 24 s, the URDF's loading most of it).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.ci.conftest import cli
from tests.paths import ROOT

BOX_PILE = ROOT / "scenarios" / "box_pile.yaml"

RESTING_COLUMN = """\
schema_version: 1
scenario: light-column
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
surface: {bounce: 0, mu: 1}
bodies:
  ground: {plane: {}, motion: static}
  crate:
    box: [0.2, 0.2, 0.2]
    mass: 1
    pos: [0, 0, 0.09999]
    array: {count: 20, spacing: [0, 0, 0.19999]}
"""

SLIPPERY_CONE = """\
schema_version: 1
scenario: sticky-cone
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
surface: {bounce: 0, mu: 1000}
backend_options:
  dart: {friction: cone}
bodies:
  ground: {plane: {}, motion: static}
  crate: {box: [0.2, 0.2, 0.2], mass: 1, pos: [0, 0, 0.1]}
"""

LOOP = """\
schema_version: 1
scenario: loop
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
bodies:
  ground: {plane: {}, motion: static}
  a: {box: [0.1, 0.1, 0.1], mass: 1, pos: [0, 0, 1]}
  b: {box: [0.1, 0.1, 0.1], mass: 1, pos: [0.2, 0, 1]}
joints:
  ab: {type: hinge, bodies: [a, b], axis: [0, 1, 0], anchor: [0.1, 0, 1]}
  ba: {type: hinge, bodies: [b, a], axis: [0, 1, 0], anchor: [0.1, 0, 1.05]}
"""

CHAIN_HEAD = """\
schema_version: 1
scenario: chain
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
bodies:
  ground: {plane: {}, motion: static}
robots:
  c: {urdf: chain.urdf, pos: [0, 0, 0.1]}
"""


def _chain_urdf(links: int) -> str:
    """``links`` 0.1 m boxes, each on a hinge 0.1 m above the previous one: a column the links make."""
    parts = ['<robot name="chain">']
    for i in range(links):
        parts.append(f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
                     f'ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry><box size="0.05 0.05 0.1"/>'
                     "</geometry></collision></link>")  # fmt: skip
    for i in range(1, links):
        parts.append(f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child link="l{i}"/>'
                     '<origin xyz="0 0 0.1"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="10" '
                     'velocity="1"/></joint>')  # fmt: skip
    return "\n".join([*parts, "</robot>"])


def _scenario(tmp_path: Path, name: str) -> Path:
    if name == "box_pile":
        return BOX_PILE
    path = tmp_path / f"{name}.yaml"
    if name == "chain":
        (tmp_path / "chain.urdf").write_text(_chain_urdf(60))
        path.write_text(CHAIN_HEAD)
    else:
        path.write_text({"resting_column": RESTING_COLUMN, "slippery_cone": SLIPPERY_CONE, "loop": LOOP}[name])
    return path


CASES = [  # (scenario, --set items, backend, what the refusal says)
    ("box_pile", ["params.count=50"], "pybullet", "column of 50 bodies; PyBullet holds at most 30"),
    ("box_pile", ["params.count=50"], "ode", "column of 50 bodies dropped onto each other"),
    ("box_pile", ["params.count=51"], "mujoco", "column of 51 bodies; MuJoCo holds at most 50"),
    ("resting_column", [], "ode", "resting column of 20 bodies with friction"),
    ("chain", [], "mujoco", "column of 60 bodies; MuJoCo holds at most 50"),
    ("chain", [], "pybullet", "column of 60 bodies; PyBullet holds at most 30"),
    ("slippery_cone", [], "dart", "NsgsFrictionSolver"),
    ("loop", [], "pybullet", "joint `ba`: it closes a loop of joints"),
    ("loop", [], "mujoco", "joint `ba` closes a kinematic loop"),
    ("loop", [], "dart", "joint `ba` of scenario `loop` makes a closed loop of joints"),
    ("loop", [], "drake", "joint `ba` closes a loop"),
    ("box_pile", [], "drake", "needs contact:bounce, which backend `drake` does not support"),
    ("resting_column", [], "drake", "column of 20 bodies; Drake is measured to hold at most 7"),
]


@pytest.mark.parametrize(("name", "sets", "backend", "says"), CASES, ids=[f"{c[0]}-{c[2]}" for c in CASES])
def test_validate_and_run_refuse_alike(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, sets: list[str], backend: str, says: str
) -> None:
    pytest.importorskip({"ode": "panda3d.ode", "dart": "dartpy", "drake": "pydrake"}.get(backend, backend))
    scenario = _scenario(tmp_path, name)
    extra = [item for s in sets for item in ("--set", s)]
    code, validated = cli(capsys, "validate", scenario, "--backend", backend, *extra)
    assert code == 2, validated
    run_code, ran = cli(capsys, "run", scenario, "--backend", backend, "--out", tmp_path / "out", *extra)
    assert run_code == 2, ran
    first = validated.strip().splitlines()[0]
    assert first.startswith("error: ") and says in first, validated
    assert first in ran.splitlines(), (validated, ran)  # run's own line for the case (stderr)
    assert "Traceback" not in validated + ran
    assert not list((tmp_path / "out").glob("*.mcap*")), "a refused run writes no trace"


def test_the_same_scenario_validates_on_a_backend_that_holds_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The limits are each engine's own: 50 boxes are refused on PyBullet and held by MuJoCo (up to 50)."""
    pytest.importorskip("mujoco")
    code, out = cli(capsys, "validate", BOX_PILE, "--backend", "mujoco", "--set", "params.count=50")
    assert code == 0, out
