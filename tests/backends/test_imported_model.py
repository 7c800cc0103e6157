"""``Backend.imported_model()`` on every installed engine: a URDF as the engine holds it once built, read back from
the engine, against the file's own numbers parsed here with xml.etree (not with the project's loader). Two files:
kuka_arm's (pybullet_data's KUKA iiwa: stops, damping, 12-digit pi in its rpy) and pendulum5's (turned, offset
inertials with products of inertia, continuous joints, the robot placed by pos and hpr: an engine that keeps a
joint axis in the link's inertial frame shows here).

Tolerance (the comparison's own rule, reports.imports.tolerance): the file's numbers are exact inputs and the
truth here is float64 arithmetic on them, so an engine's read may differ by the roundings of its float format
(reports.imports.ROUNDINGS eps: stored once, placed and read back through rotations kept in that format)
relative to the value's scale, or by half a unit in the last of the file's most precise digits, whichever is
larger. Scales: a mass its value, principal moments the largest, a COM the body's distance from the world origin
plus the COM's (it is read through world positions), an axis 1, a stop its magnitude.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from backends.base import Backend
from backends.types import ImportedModel, JointKind, Precision
from reports.imports import tolerance
from runner.compile.program import build_program
from runner.exec.imports import file_digits
from runner.language.load import load_scenario
from tests.paths import ROOT

#: (scenario, its robot's name); "legs" is written below
CASES = {"kuka_arm": ("kuka_arm.yaml", "arm"), "pendulum5": ("pendulum5.yaml", "p"), "legs": ("", "legs")}


def _link(name: str, mass: float, com_z: float, moments: str, box: str) -> str:
    ixx, iyy, izz = moments.split()
    inertia = f'<inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/>'
    return (f'<link name="{name}"><inertial><mass value="{mass}"/><origin xyz="0 0 {com_z}"/>{inertia}</inertial>'
            f'<collision><geometry><box size="{box}"/></geometry></collision></link>')


def _joint(name: str, parent: str, child: str, xyz: str, lower: float, upper: float) -> str:
    return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}"/><axis xyz="0 1 0"/><limit lower="{lower}" upper="{upper}" effort="10" '
            f'velocity="5"/></joint>')


def _thigh(side: str, y: float, mass: float) -> str:
    return (_link(f"{side}_thigh", mass, -0.1, "0.02 0.018 0.005", "0.05 0.05 0.2")
            + _joint(f"{side}_hip", "torso", f"{side}_thigh", f"0 {y} -0.1", -1.0, 1.0))  # fmt: skip


def _shin(side: str, mass: float) -> str:
    return (_link(f"{side}_shin", mass, -0.15, "0.006 0.0055 0.002", "0.04 0.04 0.3")
            + _joint(f"{side}_knee", f"{side}_thigh", f"{side}_shin", "0 0 -0.2", -2.0, 0.0))  # fmt: skip


#: a branching tree (a free torso with two two-link legs of different masses), its links listed
#: breadth first (both thighs, then both shins): PyBullet's createMultiBody renumbers them depth first
#: (backends/pybullet/_build.py, _link_indices)
LEGS_URDF = (f'<robot name="legs">{_link("torso", 8.0, 0.0, "0.1 0.2 0.15", "0.3 0.2 0.1")}'
             f'{_thigh("left", 0.15, 3.0)}{_thigh("right", -0.15, 2.0)}{_shin("left", 1.5)}{_shin("right", 1.0)}'
             "</robot>")  # fmt: skip
LEGS_YAML = """schema_version: 1
scenario: legs
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.1}
bodies:
  ground: {plane: {}, motion: static}
robots:
  legs: {urdf: legs.urdf, pos: [0, 0, 1.5]}   # free: the torso is the base of one branching tree
"""


def _floats(text: str | None, default: str) -> np.ndarray:
    return np.array([float(x) for x in (text or default).split()])


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


class Urdf:
    """The file's links and joints, with the links' frames at the zero configuration (root at the origin)."""

    def __init__(self, path: Path, pos: np.ndarray, rotation: np.ndarray) -> None:
        """``pos``/``rotation``: where the scenario placed the root link."""
        root = ET.parse(path).getroot()
        self.links = {str(link.get("name")): link for link in root.findall("link")}
        self.joints = {str(joint.get("name")): joint for joint in root.findall("joint")}
        children = {j.find("child").get("link") for j in self.joints.values()}  # type: ignore[union-attr]
        base = next(name for name in self.links if name not in children)
        self.root = base  # the root link (static when the scenario welds it: `fixed: true`)
        self.frame: dict[str, tuple[np.ndarray, np.ndarray]] = {base: (pos, rotation)}
        pending = list(self.joints.values())
        while pending:
            for joint in list(pending):
                parent = joint.find("parent").get("link")  # type: ignore[union-attr]
                if parent not in self.frame:
                    continue
                origin = joint.find("origin")
                xyz = _floats(None if origin is None else origin.get("xyz"), "0 0 0")
                rpy = _floats(None if origin is None else origin.get("rpy"), "0 0 0")
                p, r = self.frame[parent]
                child = str(joint.find("child").get("link"))  # type: ignore[union-attr]
                self.frame[child] = (p + r @ xyz, r @ _rpy(*rpy))
                pending.remove(joint)

    def mass(self, link: str) -> float:
        return float(self.links[link].find("inertial/mass").get("value"))  # type: ignore[union-attr,arg-type]

    def principal(self, link: str) -> np.ndarray:
        i = {k: float(v) for k, v in self.links[link].find("inertial/inertia").attrib.items()}  # type: ignore[union-attr]
        rows = (("ixx", "ixy", "ixz"), ("ixy", "iyy", "iyz"), ("ixz", "iyz", "izz"))
        tensor = np.array([[i[k] for k in row] for row in rows])
        return np.linalg.eigvalsh(tensor)  # a rotation (the inertial rpy) keeps the principal moments

    def com(self, link: str) -> np.ndarray:
        return _floats(self.links[link].find("inertial/origin").get("xyz"), "0 0 0")  # type: ignore[union-attr]

    def child(self, joint: str) -> str:
        return str(self.joints[joint].find("child").get("link"))  # type: ignore[union-attr]

    def axis(self, joint: str) -> np.ndarray:
        return self.frame[self.child(joint)][1] @ _floats(self.joints[joint].find("axis").get("xyz"), "1 0 0")  # type: ignore[union-attr]

    def limits(self, joint: str) -> tuple[float | None, float | None]:
        """A revolute joint's stops; a continuous joint has none."""
        if self.joints[joint].get("type") == "continuous":
            return None, None
        limit = self.joints[joint].find("limit")
        return float(limit.get("lower")), float(limit.get("upper"))  # type: ignore[union-attr,arg-type]

    def damping(self, joint: str) -> float:
        dynamics = self.joints[joint].find("dynamics")
        return float(dynamics.get("damping", 0.0)) if dynamics is not None else 0.0


@pytest.fixture(scope="module", params=sorted(CASES))
def model(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> tuple[object, Urdf, int, str]:
    """(world, the file parsed here, the file's digits, the robot's name)."""
    from backends.geometry import quat_matrices

    file, robot = CASES[request.param]
    if file:
        loaded = load_scenario(ROOT / "scenarios" / "robots" / file)
    else:
        folder = tmp_path_factory.mktemp("legs")
        (folder / "legs.urdf").write_text(LEGS_URDF)
        (folder / "legs.yaml").write_text(LEGS_YAML)
        loaded = load_scenario(folder / "legs.yaml")
    path = Path(loaded.robots[robot].file)
    world = build_program(loaded).world
    root = world.bodies[world.body_index(f"{robot}.{Urdf(path, np.zeros(3), np.eye(3)).root}")]
    urdf = Urdf(path, np.asarray(root.pos, dtype=float), np.asarray(quat_matrices(root.quat), dtype=float))
    return world, urdf, file_digits([str(path)]), robot


def _read(backend_cls: type[Backend], world: object) -> ImportedModel:
    with backend_cls(world) as backend:  # type: ignore[arg-type]
        model = backend.imported_model()
    if model is None:
        pytest.fail(f"{backend_cls.name} reports no imported model (its adapter must read the world back)")
    return model


def _near(got: object, want: object, scale: float, rel: float) -> bool:
    return bool(np.max(np.abs(np.asarray(got, dtype=float) - np.asarray(want, dtype=float))) <= rel * scale)


def test_the_engine_holds_the_urdfs_masses_inertias_and_centres(backend_cls: type[Backend], model) -> None:  # noqa: ANN001
    world, urdf, digits, robot = model
    rel = tolerance(backend_cls.precision.eps, Precision.FLOAT64.eps, digits)
    model = _read(backend_cls, world)
    static = {b.name for b in world.bodies if b.motion.value == "static"}  # a root welded to the world
    moving = [name for name in urdf.links if f"{robot}.{name}" not in static]
    assert sorted(b.name for b in model.bodies) == sorted(f"{robot}.{n}" for n in moving)
    for body in model.bodies:
        link = body.name.removeprefix(f"{robot}.")
        spec = world.bodies[world.body_index(body.name)]
        reach = math.hypot(*spec.pos) + float(np.max(np.abs(urdf.com(link))))
        assert _near(body.mass, urdf.mass(link), urdf.mass(link), rel), (link, body.mass)
        want = urdf.principal(link)
        assert _near(body.inertia, want, float(want.max()), rel), (link, body.inertia, want)
        assert _near(body.com, urdf.com(link), reach, rel), (link, body.com)
        assert _near(spec.pos, urdf.frame[link][0], reach, rel)  # the body frame is the URDF's link frame
        assert body.shapes == len(urdf.links[link].findall("collision"))


def test_the_engine_holds_the_urdfs_joints(backend_cls: type[Backend], model) -> None:  # noqa: ANN001
    """Axes and stops as the file states them; damping as the engine holds it: its own joint damping where the
    adapter gives the engine the file's damping (``native_damping``), else none (the runner's motor applies it)."""
    world, urdf, digits, robot = model
    rel = tolerance(backend_cls.precision.eps, Precision.FLOAT64.eps, digits)
    model = _read(backend_cls, world)
    assert sorted(j.name for j in model.joints) == sorted(f"{robot}.{n}" for n in urdf.joints)
    for joint in model.joints:
        name = joint.name.removeprefix(f"{robot}.")
        assert joint.kind is JointKind.HINGE  # every joint of both files is revolute or continuous
        assert joint.axis is not None and _near(joint.axis, urdf.axis(name), 1.0, rel), (name, joint.axis)
        lo, hi = urdf.limits(name)
        if lo is None or hi is None:
            assert joint.lo is None and joint.hi is None, (name, joint.lo, joint.hi)
        else:
            assert joint.lo is not None and joint.hi is not None
            assert _near([joint.lo, joint.hi], [lo, hi], max(abs(lo), abs(hi)), rel), (name, joint.lo, joint.hi)
        if backend_cls.native_damping:
            assert joint.damping == pytest.approx(urdf.damping(name), rel=rel)
        else:
            assert joint.damping in (None, 0.0)


def test_each_body_is_read_where_the_world_placed_it(backend_cls: type[Backend], model) -> None:  # noqa: ANN001
    """Before any step every link's state is its own placement (a body read from another link's slot shows here:
    PyBullet renumbers a branching tree's links)."""
    world, _, _, _ = model
    with backend_cls(world) as backend:
        states = backend.body_states()
    rel = tolerance(backend_cls.precision.eps, Precision.FLOAT64.eps, 17)
    for i, spec in enumerate(world.bodies):
        if spec.motion.value == "dynamic":
            reach = math.hypot(*spec.pos) + math.hypot(*spec.com)
            assert _near(states.pos[i], spec.pos, reach, rel), (spec.name, states.pos[i], spec.pos)


def test_the_read_is_of_the_world_as_built(backend_cls: type[Backend], model) -> None:  # noqa: ANN001
    """After a step the bodies have moved: the contract refuses to call that the import."""
    from backends.errors import ContractViolation

    world, _, _, _ = model
    with backend_cls(world) as backend:
        backend.step()
        with pytest.raises(ContractViolation, match="imported_model"):
            backend.imported_model()
