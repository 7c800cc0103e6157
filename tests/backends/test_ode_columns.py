"""ODE's refusal of resting columns (issue 27): a column of more than 4 bodies that starts resting, with
friction, is refused before the run, since dWorldStep's single-precision LCP fails on the redundant friction
rows of its stacked faces and kicks it (docs/backends/ode.md, Stacking: the issue's 20 boxes of 1 kg fall
2.2 m; conformance 16's 5 to 30 boxes of 13.5 kg move 1.7-8.4 mm). The limit's edges: conformance 12's 4
boxes, a frictionless column (no friction rows: 0.07 mm measured), a landing column (MAX_LANDING_STACK's
rule) and a robot's links above one another (a chain held by joints, not a stack) are accepted.
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("panda3d.ode")

from backends.errors import UnsupportedFeature  # noqa: E402
from backends.ode._options import MAX_LANDING_STACK, MAX_RESTING_STACK  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.types import BodySpec, JointKind, JointSpec, Surface  # noqa: E402
from tests.ci.conftest import cli  # noqa: E402

SIDE = 0.2
DENSITY = 1.0 / SIDE**3  # 1 kg boxes of 0.2 m, as in the issue

# The issue's column: 20 boxes of 1 kg and 0.2 m, each 1e-5 m into the one below, dt 0.01, mu 1, 5 s.
ISSUE_COLUMN = """\
schema_version: 1
scenario: light-column
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 5.0}
surface: {bounce: 0, mu: 1}
bodies:
  ground: {plane: {}, motion: static}
  crate:
    box: [0.2, 0.2, 0.2]
    mass: 1
    pos: [0, 0, 0.09999]
    array: {count: 20, spacing: [0, 0, 0.19999]}
assertions:
  - {name: top-box-stays, max: "max(max(crate.pos.x), -min(crate.pos.x))", near: 0, tol: 1e-3}
"""


def _column(n: int, gap: float) -> list[BodySpec]:
    """n boxes of 1 kg, box i at SIDE/2 + gap + i (SIDE + gap) (gap < 0: each one into the one below)."""
    return [w.box(f"crate_{i}", (SIDE,) * 3, (0.0, 0.0, SIDE / 2 + gap + i * (SIDE + gap)), density=DENSITY)
            for i in range(n)]  # fmt: skip


def _build(bodies: list[BodySpec], **kw: object) -> None:
    with w.make_backend("ode", w.world("column", [w.ground(), *bodies], **kw)):  # type: ignore[arg-type]
        pass


def test_the_issues_column_is_refused_on_ode_with_exit_2_and_accepted_on_mujoco(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scenario = tmp_path / "light_column.yaml"
    scenario.write_text(ISSUE_COLUMN)
    code, out = cli(capsys, "run", scenario, "--backend", "ode")
    assert code == 2, out
    assert "resting column of 20 bodies with friction" in out and f"at most {MAX_RESTING_STACK}" in out
    assert "mujoco" in out and "pybullet" in out and "dart" in out and "Traceback" not in out
    code, out = cli(capsys, "validate", scenario, "--backend", "mujoco")
    assert code == 0, out


@pytest.mark.parametrize("n", [MAX_RESTING_STACK + 1, 20, 30])
def test_a_resting_column_with_friction_above_the_limit_is_refused(n: int) -> None:
    with pytest.raises(UnsupportedFeature, match=f"resting column of {n} bodies"):
        _build(_column(n, gap=-1e-5))


def test_conformance_12s_four_boxes_are_accepted() -> None:
    _build(_column(MAX_RESTING_STACK, gap=-1e-5))


def test_a_frictionless_resting_column_is_accepted() -> None:
    _build(_column(20, gap=-1e-5), surface=Surface(bounce=0.0, mu=0.0))


def test_a_landing_column_up_to_its_own_limit_is_accepted() -> None:
    _build(_column(MAX_LANDING_STACK, gap=0.02))


def test_a_robots_links_above_one_another_are_not_a_column() -> None:
    links = _column(MAX_RESTING_STACK + 2, gap=-1e-5)
    joints = tuple(
        JointSpec(f"j{i}", JointKind.HINGE, links[i].name, links[i - 1].name if i else None,
                  axis=(1.0, 0.0, 0.0), anchor=(0.0, 0.0, SIDE * i))  # fmt: skip
        for i in range(len(links))
    )
    _build(links, joints=joints)
