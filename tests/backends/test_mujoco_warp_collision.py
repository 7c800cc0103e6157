"""mujoco_warp's box-box contacts are MuJoCo's (backends/mujoco_warp/_backend.py, ``box_box_as_mujoco``).

MJWarp's default box-box collider (its convex GJK/EPA path) found no contact for a 0.1 m cube 1.19 mm into a
4 x 4 x 0.1 m box, a state a box drop reached (the cube then fell through the ground; mujoco_warp issues 1430,
1526); MuJoCo finds the cube's 4 bottom corners. With MJWarp's analytic collider (MuJoCo's ``mjc_BoxBox``) the
contacts are MuJoCo's: the same count, and depths equal within float32 (a corner's depth is the cube's centre
plus its rotated half size less the ground's top, at most 6 float32 roundings of values up to 0.05 m, each
2^-24 x 0.05 = 3e-9 m: 2e-8 m).
"""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco_warp")

from backends.registry import create_backend  # noqa: E402
from backends.testing import worlds as w  # noqa: E402
from backends.types import CompiledWorld, Motion, Surface  # noqa: E402

DEPTH = 1.18686701e-3  # the drop's state: the cube's centre at z = -DEPTH, the ground's top at -0.05
#: and the cube's offset and tilt in that state (a few 1e-7 m and rad: the exactly level cube is found either way)
OFFSET = (4.70861693e-07, 4.15986278e-07)
TILT = (1.0, -1.93443995e-07, 7.66063863e-07, -6.61812076e-13)


def _cube_into_ground() -> CompiledWorld:
    ground = w.box("ground", (4.0, 4.0, 0.1), (0.0, 0.0, -0.1), motion=Motion.STATIC)
    cube = w.box("cube", (0.1, 0.1, 0.1), (*OFFSET, -DEPTH), density=7000.0, quat=TILT)  # 7 kg
    return w.world("drop", [ground, cube], dt=0.004, surface=Surface(bounce=0.7, mu=1.0))


def test_a_cube_on_a_larger_box_has_mujocos_four_contacts() -> None:
    world = _cube_into_ground()
    depths = {}
    for engine in ("mujoco", "mujoco_warp"):
        with create_backend(engine, world) as sim:
            sim.step()  # the contacts of the step's start, where the cube is DEPTH into the ground
            depths[engine] = sorted(p.depth for p in sim.contact_points())
    assert len(depths["mujoco"]) == 4
    assert len(depths["mujoco_warp"]) == 4
    assert depths["mujoco_warp"] == pytest.approx(depths["mujoco"], abs=2e-8)
    assert depths["mujoco"] == pytest.approx([DEPTH] * 4, abs=1e-6)  # the tilt: 1e-6 rad x 0.05 m
