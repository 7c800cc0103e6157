"""MJCF's legacy dialect (runner.language.mjcf_legacy, docs/robots.md "MJCF's legacy dialect"): each construct
converted as older MuJoCo read it, said in a note, and what cannot be converted refused at its line and column.

The global-coordinate conversion is checked against MuJoCo itself: a file written in global coordinates and
the same model written by hand in local ones compile to the same world poses, joint anchors and axes and geom
poses (to 1e-12: both are double arithmetic on the same numbers); every orientation form (quat, axisangle,
euler in both conventions and units, xyaxes, zaxis) is read as MuJoCo reads it (1e-12).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from runner.language.mjcf_global import Compiler
from runner.language.mjcf_legacy import upgrade
from runner.language.robot_desc import ModelFileError

mujoco = pytest.importorskip("mujoco", reason="reading MJCF needs MuJoCo's compiler (the `mujoco` extra)")
TOL = 1e-12  # double rounding on numbers of order 1 (module docstring)

#: one arm: a body at (1, 0, 0.5) turned 90 degrees about z, a child 0.4 m along the parent's x (world y),
#: turned 30 degrees about its own y; hinges at each body's origin about local y and x; capsules along them;
#: and a free body (its geom's `pos` given: a geom without one is at the world's origin in global coordinates)
GLOBAL = """<mujoco>
  <compiler coordinate="global" angle="degree" eulerseq="zyx"/>
  <worldbody>
    <body name="a" pos="1 0 0.5" euler="90 0 0">
      <joint name="ja" type="hinge" pos="1 0 0.5" axis="-1 0 0"/>
      <geom type="capsule" fromto="1 0 0.5 1 0.4 0.5" size="0.05"/>
      <site name="tip" pos="1 0.4 0.5"/>
      <body name="b" pos="1 0.4 0.5" quat="{q}">
        <joint name="jb" type="hinge" pos="1 0.4 0.5" axis="{x}"/>
        <geom type="box" pos="{box}" size="0.05 0.05 0.05" quat="{q}"/>
        <inertial pos="{com}" mass="1" diaginertia="0.01 0.01 0.01"/>
      </body>
    </body>
    <body name="c" pos="0 0 2"><freejoint/><geom size="0.1" pos="0 0 2"/></body>
  </worldbody>
</mujoco>
"""
LOCAL = """<mujoco>
  <compiler angle="degree"/>
  <worldbody>
    <body name="a" pos="1 0 0.5" axisangle="0 0 1 90">
      <joint name="ja" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.05"/>
      <site name="tip" pos="0.4 0 0"/>
      <body name="b" pos="0.4 0 0" axisangle="0 1 0 30">
        <joint name="jb" type="hinge" axis="1 0 0"/>
        <geom type="box" pos="0.1 0 0" size="0.05 0.05 0.05"/>
        <inertial pos="0.05 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
      </body>
    </body>
    <body name="c" pos="0 0 2"><freejoint/><geom size="0.1"/></body>
  </worldbody>
</mujoco>
"""


def _global_text() -> str:
    """GLOBAL with b's world orientation (a's, 90 degrees about z, then 30 degrees about a's y) and what it
    turns: b's x axis in the world, its box 0.1 m and its centre of mass 0.05 m along it."""
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    x = np.array([0.0, c, -s])  # Rz(90) Ry(30) (1, 0, 0)
    half_z, half_y = math.radians(45), math.radians(15)
    w1, z1, w2, y2 = math.cos(half_z), math.sin(half_z), math.cos(half_y), math.sin(half_y)
    quat = (w1 * w2, -z1 * y2, w1 * y2, z1 * w2)  # (w1 + z1 k)(w2 + y2 j)
    origin = np.array([1.0, 0.4, 0.5])

    def text(values: Any) -> str:
        return " ".join(repr(float(v)) for v in values)

    return GLOBAL.replace("{q}", text(quat)).replace("{x}", text(x)).replace("{box}", text(origin + 0.1 * x)) \
        .replace("{com}", text(origin + 0.05 * x))  # fmt: skip


def _compiled(file: Path) -> Any:
    up = upgrade(file)
    if up is None:
        return mujoco.MjModel.from_xml_path(str(file))
    spec = mujoco.MjSpec.from_string(up.text)
    spec.modelfiledir = str(file.parent)
    return spec.compile()


def _poses(model: Any) -> dict[str, np.ndarray]:
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    return {"xpos": data.xpos, "xquat": data.xquat, "xipos": data.xipos, "xanchor": data.xanchor,
            "xaxis": data.xaxis, "geom_xpos": data.geom_xpos, "geom_xmat": data.geom_xmat,
            "site_xpos": data.site_xpos, "geom_size": model.geom_size}  # fmt: skip


def test_global_coordinates_compile_to_the_same_world_as_the_local_model(tmp_path: Path) -> None:
    (tmp_path / "global.xml").write_text(_global_text())
    (tmp_path / "local.xml").write_text(LOCAL)
    up = upgrade(tmp_path / "global.xml")
    assert up is not None and 'coordinate="global"' in up.notes[0] and "line 2" in up.notes[0]
    converted, expected = _poses(_compiled(tmp_path / "global.xml")), _poses(_compiled(tmp_path / "local.xml"))
    for field, values in expected.items():
        assert np.allclose(converted[field], values, atol=TOL, rtol=0), (field, converted[field], values)


@pytest.mark.parametrize(
    ("attribute", "compiler"),
    [
        ('quat="0.9 0.1 -0.3 0.2"', ""),
        ('axisangle="1 2 3 40"', ""),
        ('axisangle="1 2 3 0.7"', 'angle="radian"'),
        ('euler="10 20 30"', ""),
        ('euler="10 20 30"', 'eulerseq="XYZ"'),
        ('euler="0.1 -0.2 0.3"', 'angle="radian" eulerseq="zyx"'),
        ('euler="10 20 30"', 'eulerseq="ZXZ"'),
        ('xyaxes="1 1 0 -1 2 0.5"', ""),
        ('zaxis="0.2 -0.5 1"', ""),
        ('zaxis="0 0 -1"', ""),
    ],
)
def test_every_orientation_is_read_as_mujoco_reads_it(tmp_path: Path, attribute: str, compiler: str) -> None:
    from lxml import etree

    text = f'<mujoco><compiler {compiler}/><worldbody><body name="b" {attribute}><geom size="0.1"/></body>' \
           "</worldbody></mujoco>"  # fmt: skip
    (tmp_path / "m.xml").write_text(text)
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "m.xml"))
    expected = np.zeros(9)
    mujoco.mju_quat2Mat(expected, model.body_quat[1])
    root = etree.fromstring(text)
    ours = Compiler(root).rotation(tmp_path / "m.xml", root.find("worldbody/body"))
    assert np.allclose(ours, expected.reshape(3, 3), atol=TOL, rtol=0)


def _write(tmp_path: Path, body: str, head: str = '<compiler coordinate="global"/>') -> Path:
    path = tmp_path / "m.xml"
    path.write_text(f"<mujoco>\n  {head}\n{body}</mujoco>\n")
    return path


@pytest.mark.parametrize(
    ("body", "line", "what"),
    [
        ('  <default>\n    <geom pos="0 0 1"/>\n  </default>\n  <worldbody/>\n', 4, "<default> <geom pos>"),
        ('  <worldbody>\n    <frame pos="1 0 0"/>\n  </worldbody>\n', 4, "<frame>"),
        ('  <include file="other.xml"/>\n  <worldbody/>\n', 3, "<include>"),
    ],
)
def test_what_global_coordinates_cannot_convert_is_refused_at_its_line(
    tmp_path: Path, body: str, line: int, what: str
) -> None:
    (tmp_path / "other.xml").write_text("<mujoco/>")
    with pytest.raises(ModelFileError) as caught:
        upgrade(_write(tmp_path, body))
    assert caught.value.line == line and what in caught.value.message and caught.value.column > 0


def test_a_fixed_joint_welds_its_body_and_what_names_it_goes(tmp_path: Path) -> None:
    path = _write(
        tmp_path,
        """  <worldbody>
    <body name="base" pos="0 0 1">
      <joint name="root" type="fixed"/>
      <geom size="0.1"/>
      <body name="arm" pos="0.2 0 0">
        <joint name="hinge" axis="0 1 0"/>
        <geom size="0.05" material="steel"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="hold" joint="root"/>
    <motor name="turn" joint="hinge"/>
  </actuator>
  <sensor>
    <actuatorfrc actuator="hold"/>
    <jointpos joint="hinge"/>
  </sensor>
""",
        head="<compiler/>",
    )
    up = upgrade(path)
    assert up is not None
    model = _compiled(path)
    assert model.njnt == 1 and model.body_jntnum[1] == 0  # welded to the world: MuJoCo's body without a joint
    assert [model.actuator(i).name for i in range(model.nu)] == ["turn"] and model.nsensor == 1
    notes = " ".join(up.notes)
    assert "joint `root` (line 5)" in notes and "`steel`" in notes and "<motor> `hold` (line 14)" in notes
    assert "<actuatorfrc> (line 18)" in notes
    assert up.text.count("\n") == path.read_text().count("\n") - 1  # every line where it was (but the last break)


@pytest.mark.parametrize(("mode", "contacts"), [("all", (1, 1)), ("dynamic", (1, 0)), ("predefined", (0, 1))])
def test_option_collision_is_migrated_as_mujocos_changelog_says(tmp_path: Path, mode: str, contacts: tuple) -> None:
    """(geoms that collide by contype/conaffinity, explicit pairs) after the migration."""
    path = _write(
        tmp_path,
        """  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="ball" pos="0 0 0.1"><freejoint/><geom name="ball" size="0.1" contype="3"/></body>
  </worldbody>
  <contact><pair geom1="floor" geom2="ball"/></contact>
""",
        head=f'<option collision="{mode}"/>',
    )
    model = _compiled(path)
    dynamic = int(any(model.geom_contype[g] or model.geom_conaffinity[g] for g in range(model.ngeom)))
    assert (dynamic, model.npair) == contacts


def test_a_plane_without_grid_spacing_and_an_inertial_without_pos(tmp_path: Path) -> None:
    path = _write(
        tmp_path,
        """  <worldbody>
    <geom name="floor" type="plane" size="5 5"/>
    <body name="b" pos="0 0 1"><freejoint/><geom size="0.1"/><inertial mass="2" diaginertia="1 1 1"/></body>
  </worldbody>
""",
        head="<compiler/>",
    )
    model = _compiled(path)
    assert list(model.geom_size[0]) == [5.0, 5.0, 1.0] and list(model.body_ipos[1]) == [0.0, 0.0, 0.0]
    assert model.body_mass[1] == 2.0


def test_a_current_file_is_handed_to_mujoco_as_it_is(tmp_path: Path) -> None:
    assert upgrade(_write(tmp_path, LOCAL.split("\n", 2)[2].rsplit("</mujoco>", 1)[0], head="")) is None
