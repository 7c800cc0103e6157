"""`inertia:` on a body (runner.language.model_inertia): the three forms compile to the principal moments and
axes BodySpec holds, whose tensor is the one written (exact up to float64 rounding of an eigen-decomposition
of a 3x3 matrix of size <= 1: 1e-12); what is no rigid body's inertia is refused at the key, exit 2."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from runner.compile.program import build_program
from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario

HEAD = """\
schema_version: 1
scenario: i
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
bodies:
"""


def world_of(tmp_path: Path, bodies: str):  # noqa: ANN201
    path = tmp_path / "i.yaml"
    path.write_text(HEAD + bodies)
    return build_program(load_scenario(path)).world


def test_the_three_forms_give_the_tensor_written(tmp_path: Path) -> None:
    world = world_of(tmp_path, """\
  a: {box: [0.1, 0.2, 0.3], mass: 1, inertia: [0.1, 0.2, 0.25]}
  b: {box: [0.1, 0.2, 0.3], mass: 1, inertia: {moments: [0.1, 0.2, 0.25], hpr: [90, 0, 0]}}
  c: {box: [0.1, 0.2, 0.3], mass: 1, inertia: {ixx: 0.2, iyy: 0.3, izz: 0.4, ixy: 0.05, iyz: -0.02}}
  d: {box: [0.1, 0.2, 0.3], mass: 1, inertia: {ixx: 0.2, iyy: 0.3, izz: 0.4}}
  f: {box: [0.1, 0.2, 0.3], mass: 2}
""")  # fmt: skip
    a, b, c, d, f = world.bodies
    assert a.inertia == (0.1, 0.2, 0.25) and a.inertia_quat == (1.0, 0.0, 0.0, 0.0)
    # heading 90: the first principal axis along the body's y, the second along -x
    assert np.allclose(b.inertia_tensor(), np.diag([0.2, 0.1, 0.25]), atol=1e-12)
    assert np.allclose(c.inertia_tensor(), [[0.2, 0.05, 0], [0.05, 0.3, -0.02], [0, -0.02, 0.4]], atol=1e-12)
    assert d.inertia == (0.2, 0.3, 0.4) and d.inertia_quat == (1.0, 0.0, 0.0, 0.0)  # diagonal: axes kept
    assert f.inertia == pytest.approx((2 / 12 * 0.13, 2 / 12 * 0.10, 2 / 12 * 0.05), rel=1e-12)  # the box's, as before
    assert a.mass == 1.0


@pytest.mark.parametrize(
    ("inertia", "message"),
    [
        ("[0.1, 0.2, 0.35]", "triangle inequality (each at most the sum of the other two), found 0.1, 0.2, 0.35"),
        (
            "{ixx: 0.1, iyy: 0.1, izz: 0.1, ixy: 0.2}",
            "positive definite inertia (every principal moment > 0), found principal moments -0.1, 0.1, 0.3",
        ),
        ("[0, 0.2, 0.2]", "greater than 0"),
        ("{moments: [0.1, 0.2, 0.25], ixx: 1}", "either `moments`"),
        ("{ixx: 0.1, iyy: 0.1}", "found ixx, iyy"),
    ],
)
def test_what_is_no_inertia_is_refused_at_the_key(tmp_path: Path, inertia: str, message: str) -> None:
    path = tmp_path / "i.yaml"
    path.write_text(HEAD + f"  box: {{box: [0.1, 0.2, 0.3], mass: 1, inertia: {inertia}}}\n")
    with pytest.raises(ScenarioValidationError, match="bodies.box.inertia") as info:
        load_scenario(path)
    assert message in str(info.value)
    assert ":5:" in str(info.value)  # the body's line


def test_a_static_body_refuses_it_and_the_command_exits_2(tmp_path: Path) -> None:
    path = tmp_path / "i.yaml"
    path.write_text(HEAD + "  box: {box: [0.1, 0.2, 0.3], motion: static, inertia: [0.1, 0.1, 0.1]}\n")
    done = subprocess.run([sys.executable, "-m", "runner", "validate", str(path)], capture_output=True, text=True)
    assert done.returncode == 2, done.stderr
    assert "i.yaml:5:" in done.stderr and "`inertia` is for dynamic bodies" in done.stderr
    assert "Traceback" not in done.stderr
