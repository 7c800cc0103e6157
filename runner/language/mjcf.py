"""Read an MJCF file into a :class:`~runner.language.robot_desc.ModelDesc`, through MuJoCo's own compiler.

Why MuJoCo's compiler: `<include>`, default classes, `<asset>` meshes, `<compiler>` (angle, eulerseq,
meshdir, inertiafromgeom, balanceinertia...), `fromto` and frame composition are MuJoCo's semantics; only
MuJoCo computes them exactly. So whatever MuJoCo accepts is read (a file MuJoCo refuses is refused with its
message and line), and the compiled model is mapped into the engine-neutral description:

- every body a link (the world body is the static link `worldbody`), its mass, centre of mass and inertia
  as MuJoCo computed them; every geom that can collide (contype or conaffinity non-zero) a shape: primitives
  as they are, an ellipsoid and a mesh as a convex hull (docs/robots.md, MJCF);
- every joint (hinge, slide, ball, free); a body without a joint is welded to its parent;
- body pairs MuJoCo never lets touch (contype/conaffinity of all their geoms, `<exclude>`) are excluded;
- actuators are listed (the robot's controllable joints);
- what only an engine that reads the file itself can run (several joints in one body, `<equality>`,
  `<tendon>`, joint damping/armature/friction loss/stiffness, explicit contact pairs, a massless moving
  body, fluid forces) is recorded in :attr:`ModelDesc.needs` as capabilities: MuJoCo, which builds the
  robot from the file (backends/mujoco), runs it; another engine refuses it before the run.

Sites, cameras, lights, `<custom>`, `<sensor>`, `<visual>`, `<statistic>`, `<keyframe>` do not change the
dynamics of a step and are not read.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import Mesh, PlacedShape, Shape, ShapeKind
from runner.language.robot_desc import (
    ActuatorDesc,
    JointDesc,
    LinkDesc,
    ModelDesc,
    ModelFileError,
    ModelNeed,
    quat4,
    vec,
)
from runner.language.urdf import parse_xml
from runner.language.visuals import mjcf_visuals, within_budget

_JOINTS = {0: "free", 1: "ball", 2: "slider", 3: "hinge"}  # mjtJoint
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
#: Subdivisions of the icosphere whose hull stands for an ellipsoid on engines without one: 642 vertices,
#: every one on the ellipsoid; the hull lies inside it by at most 0.3 % of the largest radius.
ELLIPSOID_SUBDIVISIONS = 3
_ACTUATOR_KINDS = {  # (gaintype, biastype, dyntype) -> the MJCF shortcut it was written as
    (0, 0, 0): "motor",
    (0, 1, 0): "position",
}


def _mujoco(file: Path) -> Any:
    try:
        import mujoco
    except ImportError:
        raise ModelFileError(
            file,
            0,
            "reading MJCF needs MuJoCo's compiler: pip install 'physics-scenarios[mujoco]' (URDF models load "
            "without it)",
        ) from None
    return mujoco


def compile_file(file: Path) -> Any:
    """MuJoCo's compiled model of ``file`` (ModelFileError with MuJoCo's message and line when it refuses)."""
    mujoco = _mujoco(file)
    try:
        return mujoco.MjModel.from_xml_path(str(file))
    except ValueError as exc:
        found = re.search(r"line (\d+)", str(exc))
        where = re.search(r"[Ff]ile[: ]+'?([^'\n]+\.xml)", str(exc))
        owner = Path(where.group(1)) if where and Path(where.group(1)).is_file() else file
        line = int(found.group(1)) if found else 0
        raise ModelFileError(owner, line, f"MuJoCo refused the model: {exc}") from None


def _hull(points: np.ndarray, source: str) -> Mesh:
    import trimesh

    hull = trimesh.Trimesh(vertices=points, process=True).convex_hull
    vertices = tuple(vec(v) for v in np.asarray(hull.vertices, dtype=float))
    faces = tuple((int(a), int(b), int(c)) for a, b, c in np.asarray(hull.faces))
    return Mesh(vertices=vertices, faces=faces, source=source)


def _ellipsoid(radii: np.ndarray) -> Mesh:
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=ELLIPSOID_SUBDIVISIONS, radius=1.0)
    return _hull(np.asarray(sphere.vertices) * radii, "ellipsoid")


def geom_shape(model: Any, g: int, mujoco: Any) -> Shape | None:
    """A geom's shape in its own frame; None for a kind no engine here collides with (height field, SDF)."""
    kind, size, t = int(model.geom_type[g]), model.geom_size[g], mujoco.mjtGeom
    if kind == t.mjGEOM_PLANE:
        return Shape(ShapeKind.PLANE)
    if kind == t.mjGEOM_SPHERE:
        return Shape(ShapeKind.SPHERE, radius=float(size[0]))
    if kind == t.mjGEOM_CAPSULE:
        return Shape(ShapeKind.CAPSULE, radius=float(size[0]), length=2.0 * float(size[1]))
    if kind == t.mjGEOM_CYLINDER:
        return Shape(ShapeKind.CYLINDER, radius=float(size[0]), length=2.0 * float(size[1]))
    if kind == t.mjGEOM_BOX:
        return Shape(ShapeKind.BOX, size=vec(2.0 * size))
    if kind == t.mjGEOM_ELLIPSOID:
        return Shape(ShapeKind.CONVEX, mesh=_ellipsoid(np.asarray(size, dtype=float)))
    if kind == t.mjGEOM_MESH:  # MuJoCo collides with the hull of the mesh's vertices (in the geom frame)
        mesh = int(model.geom_dataid[g])
        start, count = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        points = np.asarray(model.mesh_vert[start : start + count], dtype=float)
        return Shape(ShapeKind.CONVEX, mesh=_hull(points, model.mesh(mesh).name or f"mesh_{mesh}"))
    return None


def _lines(tree: Any) -> dict[tuple[str, str], int]:
    """(tag, name) -> line, for every named element of the main file."""
    return {(e.tag, e.get("name")): e.sourceline or 0 for e in tree.getroot().iter() if isinstance(e.tag, str)
            and e.get("name")}  # fmt: skip


def _first_line(tree: Any, tag: str) -> int:
    found = next(iter(tree.getroot().iter(tag)), None)
    return (found.sourceline or 0) if found is not None else 0


def _names(model: Any, file: Path, lines: dict[tuple[str, str], int]) -> tuple[list[str], list[str]]:
    """Every body's and joint's name in the description: the file's, else `body_<i>`, `<body>_joint` (the
    k-th unnamed joint of a body with several: `<body>_joint<k>`), `<body>_free`."""
    bodies = ["worldbody"] + [model.body(i).name or f"body_{i}" for i in range(1, model.nbody)]
    joints = []
    for j in range(model.njnt):
        body = int(model.jnt_bodyid[j])
        name = model.joint(j).name
        if not name:
            count, k = int(model.body_jntnum[body]), j - int(model.body_jntadr[body])
            suffix = "free" if int(model.jnt_type[j]) == 0 else ("joint" if count == 1 else f"joint{k}")
            name = f"{bodies[body]}_{suffix}"
        joints.append(name)
    for kind, names in (("body", bodies), ("joint", joints)):
        for n in names:
            if not _IDENT.match(n):
                raise ModelFileError(file, lines.get((kind, n), 0),
                                     f"{kind} name `{n}` is not an identifier (letters, digits, `_`)")  # fmt: skip
    return bodies, joints


def _needs(model: Any, tree: Any, bodies: list[str], lines: dict[tuple[str, str], int]) -> list[ModelNeed]:
    """What only an engine reading the file itself runs (module docstring), once per capability."""
    out: dict[str, ModelNeed] = {}

    def need(capability: str, what: str, line: int) -> None:
        out.setdefault(capability, ModelNeed(capability, what, line))

    for b in range(1, model.nbody):
        if int(model.body_jntnum[b]) > 1:
            need(
                "joint:several-per-body",
                f"body `{bodies[b]}` moves on several joints",
                lines.get(("body", bodies[b]), 0),
            )
        if model.body_mass[b] <= 0 and int(model.body_jntnum[b]) > 0:
            need("body:massless", f"body `{bodies[b]}` moves but has no mass", lines.get(("body", bodies[b]), 0))
    for attr, what in (("dof_damping", "damping"), ("dof_armature", "armature"), ("dof_frictionloss", "friction loss"),
                       ("jnt_stiffness", "stiffness")):  # fmt: skip
        if np.any(getattr(model, attr) != 0):
            need("joint:dynamics", f"joint {what}", _first_line(tree, "joint"))
    if any(model.jnt_limited[j] and int(model.jnt_type[j]) == 1 for j in range(model.njnt)):
        need("joint:ball-range", "a ball joint's range", _first_line(tree, "joint"))
    if model.neq:
        need("constraint:equality", "<equality>", _first_line(tree, "equality"))
    if model.ntendon:
        need("constraint:tendon", "<tendon>", _first_line(tree, "tendon"))
    if model.npair:
        need("collision:explicit-pairs", "<contact><pair>", _first_line(tree, "pair"))
    if model.opt.density or model.opt.viscosity or np.any(model.opt.wind != 0):
        need("world:fluid", "<option> density, viscosity or wind", _first_line(tree, "option"))
    return list(out.values())


def _excluded(model: Any, bodies: list[str]) -> list[tuple[str, str]]:
    """Body pairs (both with collision shapes) that MuJoCo never lets touch: no geom pair passes the
    contype/conaffinity test, or an `<exclude>` names them."""
    masks: dict[int, list[tuple[int, int]]] = {}
    for g in range(model.ngeom):
        t, a = int(model.geom_contype[g]), int(model.geom_conaffinity[g])
        if t or a:
            masks.setdefault(int(model.geom_bodyid[g]), []).append((t, a))
    out = []
    ids = sorted(masks)
    for i, a in enumerate(ids):
        for b in ids[i + 1 :]:
            if not any(ta & ab or tb & aa for ta, aa in masks[a] for tb, ab in masks[b]):
                out.append((bodies[a], bodies[b]))
    for signature in model.exclude_signature:
        a, b = int(signature) >> 16, int(signature) & 0xFFFF
        out.append((bodies[a], bodies[b]))
    return out


def _actuators(model: Any, joints: list[str], lines: dict[tuple[str, str], int], mujoco: Any) -> list[ActuatorDesc]:
    out = []
    for a in range(model.nu):
        name = model.actuator(a).name or f"actuator_{a}"
        key = (int(model.actuator_gaintype[a]), int(model.actuator_biastype[a]), int(model.actuator_dyntype[a]))
        kind = _ACTUATOR_KINDS.get(key, "general")
        if kind == "position" and model.actuator_biasprm[a][1] == 0:
            kind = "velocity"  # bias (0, 0, -kv)
        on_joint = int(model.actuator_trntype[a]) in (mujoco.mjtTrn.mjTRN_JOINT, mujoco.mjtTrn.mjTRN_JOINTINPARENT)
        joint = joints[int(model.actuator_trnid[a][0])] if on_joint else None
        line = next((v for (tag, n), v in lines.items() if n == name and tag != "joint" and tag != "body"), 0)
        out.append(ActuatorDesc(name, kind, joint, line))
    return out


def load_mjcf(file: Path) -> ModelDesc:
    tree = parse_xml(file)
    mujoco = _mujoco(file)
    model = compile_file(file)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    lines = _lines(tree)
    bodies, joint_names = _names(model, file, lines)
    links = []
    for b in range(model.nbody):
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.body_iquat[b])
        r = rot.reshape(3, 3)
        tensor = r @ np.diag(model.body_inertia[b]) @ r.T
        shapes = []
        for g in range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b]):
            if not (model.geom_contype[g] or model.geom_conaffinity[g]):
                continue  # a visual geom: it never touches anything
            shape = geom_shape(model, g, mujoco)
            if shape is None:
                continue
            rgba = model.geom_rgba[g]
            color = (float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3]))
            shapes.append(PlacedShape(shape, vec(model.geom_pos[g]), quat4(model.geom_quat[g]), color))
        mass = 0.0 if b == 0 else float(model.body_mass[b])
        links.append(
            LinkDesc(
                bodies[b],
                mass,
                vec(model.body_ipos[b]),
                (vec(tensor[0]), vec(tensor[1]), vec(tensor[2])),
                vec(data.xpos[b]),
                quat4(data.xquat[b]),
                tuple(shapes),
                None,
                lines.get(("body", bodies[b]), 0),
                mjcf_visuals(model, b, mujoco, geom_shape),
            )
        )
    joints = []
    for b in range(1, model.nbody):
        parent = bodies[int(model.body_parentid[b])]
        line = lines.get(("body", bodies[b]), 0)
        if int(model.body_jntnum[b]) == 0:  # welded to its parent
            joints.append(JointDesc(f"{bodies[b]}_weld", "fixed", parent, bodies[b], (1.0, 0.0, 0.0),
                                    vec(data.xpos[b]), None, None, line))  # fmt: skip
        first = int(model.body_jntadr[b])
        for j in range(first, first + int(model.body_jntnum[b])):
            kind = _JOINTS[int(model.jnt_type[j])]
            limited = bool(model.jnt_limited[j]) and kind in ("hinge", "slider")
            lo, hi = (float(model.jnt_range[j][0]), float(model.jnt_range[j][1])) if limited else (None, None)
            anchor = vec(data.xanchor[j]) if kind != "free" else vec(data.xpos[b])
            joints.append(JointDesc(joint_names[j], kind, parent, bodies[b], vec(data.xaxis[j]), anchor, lo, hi,
                                    lines.get(("joint", joint_names[j]), line)))  # fmt: skip
    return ModelDesc(
        str(file),
        "worldbody",
        tuple(within_budget(links)),
        tuple(joints),
        needs=tuple(_needs(model, tree, bodies, lines)),
        actuators=tuple(_actuators(model, joint_names, lines, mujoco)),
        excluded=tuple(_excluded(model, bodies)),
        timestep=float(model.opt.timestep),
        gravity=vec(model.opt.gravity),
    )
