"""Link and joint names as the model file spells them: pybullet_data's quadrupeds (joints `8`...) and
dm_control's manipulator (a body `pinch site`) load; expressions read such a name quoted (`dog["8"]`); what
the trace could not keep apart (an empty name, a control character, a repeat, two names of one trace field)
is refused at its line, and a badly quoted name at the scenario's line, both with exit 2."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from reports import trace_format as tf
from runner.errors import ScenarioValidationError
from runner.language import model_names
from runner.language.expressions import compile_expression
from runner.language.load import load_scenario
from runner.language.names import written

TWO_LINKS = """\
<?xml version="1.0"?>
<robot name="two">
  <link name="LINK_A">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <link name="LINK_B">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <joint name="JOINT" type="revolute">
    <parent link="LINK_A"/><child link="LINK_B"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
</robot>
"""


def _urdf(folder: Path, a: str = "base", b: str = "8", joint: str = "9", assertion: str = "") -> Path:
    (folder / "robot.urdf").write_text(TWO_LINKS.replace("LINK_A", a).replace("LINK_B", b).replace("JOINT", joint))
    path = folder / "s.yaml"
    path.write_text(textwrap.dedent("""\
        schema_version: 1
        scenario: t
        world: {dt: 0.01, duration: 0.1}
        bodies:
          ground: {plane: {}, motion: static}
        robots:
          bot: {urdf: robot.urdf, fixed: true}
        """) + assertion)  # fmt: skip
    return path


def _assertion(expression: str) -> str:
    return f"assertions:\n  - {{name: a, value: '{expression}', at: 0, near: 0, tol: 1}}\n"


@pytest.mark.parametrize("model", ["quadruped/spirit40.urdf", "quadruped/vision60.urdf"])
def test_pybullet_quadrupeds_load_with_joints_named_by_numbers(tmp_path: Path, model: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(textwrap.dedent(f"""\
        schema_version: 1
        scenario: t
        world: {{dt: 0.01, duration: 0.1}}
        bodies:
          ground: {{plane: {{}}, motion: static}}
        robots:
          dog: {{urdf: "@pybullet_data/{model}", pos: [0, 0, 1], joints: {{"8": {{motor: {{fmax: 1}}}}}}}}
        """) + _assertion('dog["8"].position + dog.body.pos.z'))  # fmt: skip
    desc = load_scenario(path).robots["dog"]
    joints = {j.name for j in desc.joints}
    assert {str(k) for k in range(12)} <= joints and "jtoe0" in joints


def test_mjcf_body_named_with_a_space_loads(tmp_path: Path) -> None:
    dm_control = pytest.importorskip("dm_control", reason="dm_control's suite is a test dependency (dm-control)")
    suite = Path(dm_control.__file__).parent / "suite"
    (tmp_path / "common").mkdir()
    for file in (suite / "common").glob("*.xml"):
        (tmp_path / "common" / file.name).write_bytes(file.read_bytes())
    (tmp_path / "manipulator.xml").write_bytes((suite / "manipulator.xml").read_bytes())
    path = tmp_path / "s.yaml"
    path.write_text(textwrap.dedent("""\
        schema_version: 1
        scenario: t
        world: {dt: 0.01, duration: 0.1}
        bodies:
          ground: {plane: {}, motion: static}
        robots:
          hand: {mjcf: manipulator.xml}
        """) + _assertion('hand["pinch site"].pos.z'))  # fmt: skip
    assert "pinch site" in {link.name for link in load_scenario(path).robots["hand"].links}


@pytest.mark.parametrize(
    ("expression", "says"),
    [
        ('bot["99"].position', 'unknown name `bot["99"].position` in expression; did you mean `bot["9"].position`?'),
        ("bot[8].position", 'a part in brackets is a quoted name: `arm["8"].position`'),
        ('bot["8].position', "syntax error"),
        ("bot.8.position", "syntax error"),
    ],
)
def test_bad_quoting_is_refused_at_the_expression(tmp_path: Path, expression: str, says: str) -> None:
    path = _urdf(tmp_path, assertion=_assertion(expression))
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(path)
    issue = caught.value.issues[0]
    assert issue.file == str(path) and issue.line == 9 and says in issue.message, issue


def test_bad_quoting_exits_2_located(tmp_path: Path) -> None:
    path = _urdf(tmp_path, assertion=_assertion('bot["8"'))
    done = subprocess.run([sys.executable, "-m", "runner", "validate", str(path)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=120)  # fmt: skip
    out = done.stderr + done.stdout
    assert done.returncode == 2 and "Traceback" not in out, out
    assert f"{path}:9:" in out and "syntax error" in out, out


def test_quoted_names_read_the_model_names(tmp_path: Path) -> None:
    load_scenario(_urdf(tmp_path, b="pinch site", joint="8", assertion=_assertion(
        'bot["8"].position + bot["pinch site"].pos.z + bot.base.pos.z + bot["base"].speed')))  # fmt: skip


@pytest.mark.parametrize(
    ("a", "b", "joint", "line", "says"),
    [
        ("base", "", "j", 7, "a link has no name"),
        # &#9;: a tab (XML reads a literal tab in an attribute as a space)
        ("base", "a&#9;b", "j", 7, "link name 'a\\tb' holds a control character"),
        ("base", "base", "j", 7, "link name `base` is given twice (first at line 3)"),
        ("8", "_8", "j", 7, "link names `8` (line 3) and `_8` are both `_8` in the trace's messages"),
        ("pinch site", "pinch_site", "j", 7, "link names `pinch site` (line 3) and `pinch_site` are both `pinch_site`"),
    ],
)
def test_names_the_trace_cannot_keep_apart_are_refused_at_their_line(
    tmp_path: Path, a: str, b: str, joint: str, line: int, says: str
) -> None:
    path = _urdf(tmp_path, a=a, b=b, joint=joint)
    with pytest.raises(ScenarioValidationError) as caught:
        load_scenario(path)
    issue = caught.value.issues[0]
    assert issue.file == str(tmp_path / "robot.urdf") and issue.line == line and says in issue.message, issue


NAMES = ["link_7", "8", "_8", "pinch site", "a.b", "x-y", "Ünter", "  ", "9lives", "日本", "a\"b"]


@pytest.mark.parametrize("name", NAMES)
def test_the_language_and_the_trace_map_names_to_the_same_field(name: str) -> None:
    """runner.language may not import reports: two copies of the rule, checked equal here."""
    field = tf.field_name(name)
    assert model_names.field_name(name) == field
    assert model_names.IDENTIFIER.fullmatch(field) and field.isascii()
    assert (field == name) == bool(model_names.IDENTIFIER.fullmatch(name))


def test_names_are_written_quoted_where_they_are_not_identifiers() -> None:
    assert written("arm.8.position") == 'arm["8"].position'
    assert written("arm.pinch site.pos.z") == 'arm["pinch site"].pos.z'
    assert written("box.pos.z") == "box.pos.z"


@pytest.mark.parametrize(
    ("text", "names"),
    [
        ('arm["8"].position', {"arm.8.position"}),
        ("arm['pinch site'].pos.z > arm.base.pos.z", {"arm.pinch site.pos.z", "arm.base.pos.z"}),
        ('arm["_hidden"].speed', {"arm._hidden.speed"}),  # quoted: a model's name, read whole like every name
        ('arm["link_7"].speed', {"arm.link_7.speed"}),  # an identifier may be quoted too: the same name
    ],
)
def test_a_quoted_part_is_one_part_of_the_dotted_name(text: str, names: set[str]) -> None:
    assert compile_expression(text).names == names


def test_contact_takes_a_quoted_link() -> None:
    assert compile_expression('contact(arm["pinch site"], box)').call_args == {
        ("contact", ("arm.pinch site", "box"))
    }
