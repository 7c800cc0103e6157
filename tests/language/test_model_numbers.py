"""Model files get the scenario files' numeric checks (issue 31): a URDF or MJCF number that places, sizes or
weighs something is finite and within +-MAX_MAGNITUDE (1e9, the scenario language's bound); collision sizes
positive, masses not negative, a moving joint's axis not zero, mesh vertices finite; link and joint names
unique and not empty; a model file or mesh that is a symlink loop refused. Each is exit 2 from `validate` and
`run` alike, one line `model file:line:column: robots.<name>.<format>: <element>: `<field>` ...` at the
offending attribute (measured before: NaN mesh scale, NaN inertia, duplicate link or joint names and a
symlink loop were exit 70 from `run`; NaN, inf and 1e300 in origins, sizes and axes passed `validate`).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from runner.errors import ScenarioValidationError
from runner.language.load import load_scenario
from runner.language.model_base import MAX_MAGNITUDE
from tests.ci.conftest import cli

SCENARIO = """\
schema_version: 1
scenario: model-numbers
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 0.05}}
bodies:
  ground: {{plane: {{}}, motion: static}}
robots:
  r: {{{kind}: {file}, pos: [0, 0, 1]}}
"""

# One attribute per line, so that each case's line is the line of the value it changes.
URDF = """\
<robot name="r">
  <link name="base">
    <inertial>
      <origin xyz="{com}" rpy="0 0 0"/>
      <mass value="{mass}"/>
      <inertia ixx="{ixx}" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
    </inertial>
    <collision>
      <origin xyz="{box_xyz}" rpy="{box_rpy}"/>
      <geometry><box size="{box_size}"/></geometry>
    </collision>
  </link>
  <link name="{arm}">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><cylinder radius="{radius}" length="{length}"/></geometry></collision>
    <collision><geometry><sphere radius="{sphere}"/></geometry></collision>
    <collision><geometry><mesh filename="{mesh}" scale="{scale}"/></geometry></collision>
  </link>
  <link name="tip">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="{hinge}" type="revolute">
    <parent link="base"/>
    <child link="arm"/>
    <origin xyz="{joint_xyz}" rpy="0 0 0"/>
    <axis xyz="{axis}"/>
    <limit lower="{lower}" upper="1" effort="10" velocity="1"/>
  </joint>
  <joint name="{weld}" type="fixed">
    <parent link="arm"/>
    <child link="tip"/>
  </joint>
</robot>
"""
GOOD = {"com": "0 0 0", "mass": "2", "ixx": "0.01", "box_xyz": "0 0 0", "box_rpy": "0 0 0", "box_size": "0.2 0.2 0.2",
        "arm": "arm", "radius": "0.05", "length": "0.3", "sphere": "0.05", "mesh": "tet.obj", "scale": "1 1 1",
        "hinge": "hinge", "weld": "weld", "joint_xyz": "0 0 0.2", "axis": "1 0 0", "lower": "-1"}  # fmt: skip
TETRAHEDRON = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv {x} 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"

#: (case id, field changed, bad value, the attribute the error names, what it says)
URDF_CASES = [
    ("nan-origin", "com", "0 nan 0", "xyz", "is NaN"),
    ("inf-origin", "box_xyz", "0 0 inf", "xyz", "beyond"),
    ("huge-rpy", "box_rpy", "1e300 0 0", "rpy", "beyond"),
    ("zero-box", "box_size", "0 0.2 0.2", "size", "must be positive"),
    ("negative-radius", "radius", "-0.05", "radius", "must be positive"),
    ("huge-length", "length", "1e300", "length", "beyond"),
    ("nan-sphere", "sphere", "nan", "radius", "is NaN"),
    ("negative-mass", "mass", "-2", "value", "must not be negative"),
    ("nan-mass", "mass", "nan", "value", "is NaN"),
    ("nan-inertia", "ixx", "nan", "ixx", "is NaN"),
    ("huge-inertia", "ixx", "1e300", "ixx", "beyond"),
    ("nan-scale", "scale", "nan 1 1", "scale", "is NaN"),
    ("zero-scale", "scale", "0", "scale", "must not be zero"),
    ("inf-joint-origin", "joint_xyz", "0 0 -inf", "xyz", "beyond"),
    ("nan-axis", "axis", "nan 0 0", "xyz", "is NaN"),
    ("huge-axis", "axis", "1e300 1e300 0", "xyz", "beyond"),
    ("zero-axis", "axis", "0 0 0", "xyz", "is zero"),
    ("nan-limit", "lower", "nan", "lower", "is NaN"),
    ("empty-size", "box_size", "", "size", "expected 3 numbers"),
    ("one-number-axis", "axis", "-1e9", "xyz", "expected 3 numbers"),
    ("text-radius", "radius", "abc", "radius", "expected 1 number"),
    ("duplicate-link", "arm", "base", '"base"', "link name `base` is given twice"),
    ("empty-link-name", "arm", "", "name", "has no name"),
    ("duplicate-joint", "weld", "hinge", '"hinge"', "joint name `hinge` is given twice"),
]


def _write(tmp_path: Path, **changes: str) -> tuple[Path, Path]:
    values = {**GOOD, **changes}
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(URDF.format(**values))
    (tmp_path / "tet.obj").write_text(TETRAHEDRON.format(x=0))
    scenario = tmp_path / "s.yaml"
    scenario.write_text(SCENARIO.format(kind="urdf", file="robot.urdf"))
    return scenario, urdf


def _refused_alike(capsys: pytest.CaptureFixture[str], scenario: Path, tmp_path: Path) -> str:
    """Exit 2 from validate and run with the same lines, no traceback; the issues in full (the console may
    shorten a long path), one a line."""
    code, validated = cli(capsys, "validate", scenario)
    run_code, ran = cli(capsys, "run", scenario, "--out", tmp_path / "out")
    assert (code, run_code) == (2, 2), validated + ran
    assert "Traceback" not in validated + ran
    lines = [line for line in validated.splitlines() if line.strip()]
    assert all(line in ran for line in lines), (validated, ran)
    with pytest.raises(ScenarioValidationError) as info:
        load_scenario(scenario, None)
    return "\n".join(str(issue) for issue in info.value.issues)


def _located_at(text: str, file: Path, token: str) -> tuple[int, int]:
    """(line, column) of the first ``token`` in ``file`` (1-based)."""
    for number, line in enumerate(file.read_text().splitlines(), 1):
        if token in line:
            return number, line.index(token) + 1
    raise AssertionError(f"{token} not in {file}")


def test_the_good_model_runs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The model every case below spoils validates and runs, on ODE and on PyBullet (whose compound of the
    arm's mesh and two primitives takes the hull as an OBJ file: backends/pybullet/_compound.py)."""
    pytest.importorskip("panda3d.ode")
    scenario, _ = _write(tmp_path)
    for backend in ("ode", "pybullet"):
        for command in (["validate"], ["run", "--out", str(tmp_path / backend)]):
            code, out = cli(capsys, *command, scenario, "--backend", backend)
            assert code == 0, out


@pytest.mark.parametrize(("field", "value", "attribute", "says"), [c[1:] for c in URDF_CASES],
                         ids=[c[0] for c in URDF_CASES])  # fmt: skip
def test_a_bad_urdf_number_or_name_is_refused_at_its_attribute(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], field: str, value: str, attribute: str, says: str
) -> None:
    scenario, urdf = _write(tmp_path, **{field: value})
    out = _refused_alike(capsys, scenario, tmp_path)
    # the line holding the changed value (a duplicate: its second use), the column of the attribute
    template_line = next(n for n, line in enumerate(URDF.splitlines(), 1) if "{" + field + "}" in line)
    if attribute.startswith('"'):
        line = urdf.read_text().splitlines()[template_line - 1]
        column = line.index(attribute) + 1
    else:
        line = urdf.read_text().splitlines()[template_line - 1]
        column = line.index(f"{attribute}=") + 1 if f"{attribute}=" in line else 0
    where = f"{urdf}:{template_line}:{column or ''}"
    assert re.search(rf"^{re.escape(where)}\d*: robots\.r\.urdf: .*{re.escape(says)}", out, re.M), (where, out)


def test_non_finite_mesh_vertex_is_refused_at_the_mesh(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """trimesh drops a NaN vertex and its faces when it processes a mesh: checked before that."""
    scenario, urdf = _write(tmp_path)
    (tmp_path / "tet.obj").write_text(TETRAHEDRON.format(x="nan"))
    out = _refused_alike(capsys, scenario, tmp_path)
    line, column = _located_at(out, urdf, 'filename="tet.obj"')
    assert f"{urdf}:{line}:{column + len('filename=') + 1}: " in out, out
    assert "tet.obj has a vertex that is not finite" in out, out


def test_mesh_vertex_beyond_the_bound_once_scaled(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A scale within the bound (1e8) times a vertex at 100 m: 1e10 m."""
    scenario, urdf = _write(tmp_path, scale=f"{MAX_MAGNITUDE / 10:g}")
    (tmp_path / "tet.obj").write_text(TETRAHEDRON.format(x=100))
    out = _refused_alike(capsys, scenario, tmp_path)
    assert f"vertex beyond +-{MAX_MAGNITUDE:g} m" in out, out


def test_a_model_file_that_is_a_symlink_loop(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario = tmp_path / "s.yaml"
    scenario.write_text(SCENARIO.format(kind="urdf", file="loop.urdf"))
    (tmp_path / "loop.urdf").symlink_to(tmp_path / "loop.urdf")
    out = _refused_alike(capsys, scenario, tmp_path)
    assert re.search(rf"^{re.escape(str(scenario))}:7:\d+: robots\.r\.urdf: .*symlink loop", out, re.M), out


def test_a_mesh_that_is_a_symlink_loop(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario, urdf = _write(tmp_path, mesh="loop.obj")
    (tmp_path / "loop.obj").symlink_to(tmp_path / "loop.obj")
    out = _refused_alike(capsys, scenario, tmp_path)
    line, _ = _located_at(out, urdf, "loop.obj")
    assert re.search(rf"^{re.escape(str(urdf))}:{line}:\d+: .*`loop.obj` is a symlink loop", out, re.M), out


MJCF = """\
<mujoco>
  <worldbody>
    <body name="{first}" pos="{pos}">
      <freejoint/>
      <geom type="box" size="{size}" mass="{mass}"/>
    </body>
    <body pos="0 0 2">
      <joint type="hinge" axis="1 0 0" range="{range}"/>
      <geom type="sphere" size="0.1"/>
    </body>
  </worldbody>
</mujoco>
"""
MJCF_GOOD = {"first": "a", "pos": "0 0 1", "size": "0.1 0.1 0.1", "mass": "1", "range": "-1 1"}
MJCF_CASES = [
    ("nan-pos", "pos", "0 nan 1", "pos", "is NaN"),
    ("huge-size", "size", "1e300 0.1 0.1", "size", "beyond"),
    ("inf-mass", "mass", "inf", "mass", "beyond"),
    ("negative-mass", "mass", "-1", "mass", "must not be negative"),
    ("nan-range", "range", "nan 1", "range", "is NaN"),
    ("generated-name-taken", "first", "body_2", '"body_2"', "body name `body_2` is given twice"),
]


@pytest.mark.parametrize(("field", "value", "attribute", "says"), [c[1:] for c in MJCF_CASES],
                         ids=[c[0] for c in MJCF_CASES])  # fmt: skip
def test_a_bad_mjcf_number_or_name_is_refused_at_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], field: str, value: str, attribute: str, says: str
) -> None:
    pytest.importorskip("mujoco")
    model = tmp_path / "model.xml"
    model.write_text(MJCF.format(**{**MJCF_GOOD, field: value}))
    scenario = tmp_path / "s.yaml"
    scenario.write_text(SCENARIO.format(kind="mjcf", file="model.xml"))
    out = _refused_alike(capsys, scenario, tmp_path)
    template_line = next(n for n, line in enumerate(MJCF.splitlines(), 1) if "{" + field + "}" in line)
    assert re.search(rf"^{re.escape(str(model))}:{template_line}:\d+: robots\.r\.mjcf: .*{re.escape(says)}", out,
                     re.M), out  # fmt: skip


def test_a_massless_root_is_located_at_its_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Found by mutating this file's model: the issue had column 0 (unlocated); now the link's first column."""
    scenario, urdf = _write(tmp_path, mass="0")
    out = _refused_alike(capsys, scenario, tmp_path)
    assert f"{urdf}:2:3: robots.r.fixed: root link `base` has no mass" in out, out


#: what a mutated attribute becomes: non-finite, beyond the bound, text, empty, the wrong count, names taken
MUTATIONS = ["nan", "inf", "-inf", "1e400", "1e-400", "", "abc", "1 2", "0", "-0", "1e9", "-1e9", "1e10", "1,2,3",
             "NaN NaN NaN", " ", "1e308 1e308 1e308", "-1", "1_0", "Infinity", "+.5e-3", "base", "hinge"]  # fmt: skip
MUTANTS = 150


def test_mutated_models_load_or_are_refused_located(tmp_path: Path) -> None:
    """1-3 attributes of the model at a time set to MUTATIONS (a fixed seed): each model loads and compiles, or
    is refused with every issue at a line and column; never another exception (the first 300 found an empty
    box size and a one-number axis crashing the loader, and a massless root at column 0)."""
    import random

    from runner.compile.program import build_program

    rng = random.Random(31)
    (tmp_path / "tet.obj").write_text(TETRAHEDRON.format(x=0))
    scenario = tmp_path / "s.yaml"
    scenario.write_text(SCENARIO.format(kind="urdf", file="robot.urdf"))
    refused = 0
    for _ in range(MUTANTS):
        changes = {key: rng.choice(MUTATIONS) for key in rng.sample(sorted(GOOD), rng.randint(1, 3))}
        (tmp_path / "robot.urdf").write_text(URDF.format(**{**GOOD, **changes}))
        try:
            build_program(load_scenario(scenario, None))
        except ScenarioValidationError as exc:
            refused += 1
            unlocated = [str(i) for i in exc.issues if not re.match(r".+:[1-9]\d*:[1-9]\d*: ", str(i))]
            assert not unlocated, (changes, unlocated)
    assert refused > MUTANTS // 2  # most mutations break the model: the checks above are exercised


@pytest.mark.parametrize("kind", ["urdf", "mjcf"])
def test_a_model_path_the_system_refuses_is_located_at_the_scenario_s_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str
) -> None:
    """A 300-character file name (beyond NAME_MAX, 255 on Linux): `stat` raises ENAMETOOLONG, which was exit 70
    (found by the structured fuzzer); now exit 2 at the `urdf:`/`mjcf:` line, as a missing file is."""
    scenario = tmp_path / "s.yaml"
    scenario.write_text(SCENARIO.format(kind=kind, file="n" * 300 + ".xml"))
    out = _refused_alike(capsys, scenario, tmp_path)
    assert re.search(rf"^{re.escape(str(scenario))}:7:\d+: robots\.r\.{kind}: no model file at .*\(", out), out
