"""The lowest point of a model's collision shapes (runner.survey.models.lowest_point, built on
urdf_rules.shape_points), which places a survey model `CLEARANCE` above the ground.

Before: a capsule's extent along its axis was its cylinder's half-length only, without the cap's radius, so
pybullet_data's capsule.xml (radius 0.05, half-length 0.1, at z = 1) was placed 4 cm into the ground and the
energy watchdog stopped it on every engine. The extents are exact (a box's corners bound every shape here), so
the comparison is to rounding of a few operations on numbers of order 1.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from runner.language.mjcf import load_mjcf
from runner.survey.models import lowest_point

pytest.importorskip("mujoco")

EPS = 1e-12


def _model(tmp_path: Path, geom: str, z: float) -> Path:
    path = tmp_path / "m.xml"
    path.write_text(f'<mujoco><worldbody><body pos="0 0 {z}"><joint type="free"/>{geom}</body></worldbody></mujoco>')
    return path


@pytest.mark.parametrize("z", [0.3, 1.0, 2.5])
@pytest.mark.parametrize(
    ("geom", "below"),
    [
        ('<geom type="capsule" size="0.05 0.1"/>', 0.15),  # along z: half-length + radius
        ('<geom type="capsule" size="0.2 0.4"/>', 0.6),
        ('<geom type="cylinder" size="0.05 0.1"/>', 0.1),  # no caps
        ('<geom type="sphere" size="0.07"/>', 0.07),
        ('<geom type="box" size="0.1 0.2 0.3"/>', 0.3),
        ('<geom type="capsule" fromto="-0.3 0 0 0.3 0 0" size="0.05"/>', 0.05),  # lying along x: the radius
    ],
)
def test_the_lowest_point_is_the_shape_s_true_bottom(tmp_path: Path, geom: str, below: float, z: float) -> None:
    desc = load_mjcf(_model(tmp_path, geom, z))
    assert lowest_point(desc) == pytest.approx(z - below, abs=EPS * 10)
