"""Read an MJCF file into a :class:`~runner.language.robot_desc.ModelDesc`, through MuJoCo's own compiler.

Why MuJoCo's compiler: MJCF's defaults classes, `fromto`, `inertiafromgeom`, degree/radian settings and
frame composition are MuJoCo's semantics; only MuJoCo computes them exactly, and it is the well-kept
implementation. The cost: loading an MJCF scenario needs the `mujoco` extra (a URDF scenario does not).
The subset (docs/robots.md): bodies, `inertial`, geoms (plane, sphere, capsule, cylinder, box), joints
(hinge, slide, free; no stiffness, damping, armature or friction loss); lights, cameras and sites are
ignored; anything else (actuators, tendons, equality constraints, sensors, meshes, contact pairs) is refused
at its line. The `world` body's geoms become the static link `worldbody`.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import PlacedShape, Shape, ShapeKind
from runner.language.robot_desc import JointDesc, LinkDesc, ModelDesc, ModelFileError, quat4, vec
from runner.language.urdf import parse_xml

_ALLOWED = frozenset(
    {
        "mujoco",
        "compiler",
        "option",
        "size",
        "default",
        "worldbody",
        "body",
        "geom",
        "joint",
        "inertial",
        "light",
        "camera",
        "site",
        "visual",
        "statistic",
        "global",
        "quality",
        "map",
        "headlight",
        "rgba",
        "flag",
    }
)
_JOINTS = {2: "slider", 3: "hinge"}  # mjJNT_SLIDE, mjJNT_HINGE (mjJNT_FREE = 0 is a free root, mjJNT_BALL = 1 refused)
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _refuse_beyond_subset(tree: Any, file: Path) -> None:
    for element in tree.getroot().iter():
        if not isinstance(element.tag, str):
            continue
        if element.tag not in _ALLOWED:
            raise ModelFileError(
                file,
                element.sourceline or 0,
                f"<{element.tag}> is beyond the MJCF subset this runner reads (docs/robots.md)",
            )
        if element.tag == "joint" and element.get("type", "hinge") not in ("hinge", "slide", "free"):
            raise ModelFileError(
                file,
                element.sourceline or 0,
                f"joint type `{element.get('type')}` is beyond the subset (hinge, slide, free)",
            )


def _shape(kind: int, size: np.ndarray, file: Path, name: str) -> Shape:
    import mujoco

    g = mujoco.mjtGeom
    if kind == g.mjGEOM_PLANE:
        return Shape(ShapeKind.PLANE)
    if kind == g.mjGEOM_SPHERE:
        return Shape(ShapeKind.SPHERE, radius=float(size[0]))
    if kind == g.mjGEOM_CAPSULE:
        return Shape(ShapeKind.CAPSULE, radius=float(size[0]), length=2.0 * float(size[1]))
    if kind == g.mjGEOM_CYLINDER:
        return Shape(ShapeKind.CYLINDER, radius=float(size[0]), length=2.0 * float(size[1]))
    if kind == g.mjGEOM_BOX:
        return Shape(ShapeKind.BOX, size=vec(2.0 * size))
    raise ModelFileError(file, 0, f"geom `{name}` has a type beyond the subset (plane, sphere, capsule, cylinder, box)")


def load_mjcf(file: Path) -> ModelDesc:
    tree = parse_xml(file)
    _refuse_beyond_subset(tree, file)
    try:
        import mujoco
    except ImportError:
        raise ModelFileError(
            file,
            0,
            "reading MJCF needs MuJoCo's compiler: pip install "
            "'physics-scenarios[mujoco]' (URDF models load without it)",
        ) from None
    try:
        model = mujoco.MjModel.from_xml_path(str(file))
    except ValueError as exc:
        found = re.search(r"line (\d+)", str(exc))
        raise ModelFileError(file, int(found.group(1)) if found else 0, f"MuJoCo refused the model: {exc}") from None
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    lines = {e.get("name"): e.sourceline or 0 for e in tree.getroot().iter("body", "joint") if e.get("name")}
    names = ["worldbody"] + [model.body(i).name or f"body_{i}" for i in range(1, model.nbody)]
    for n in names:
        if not _IDENT.match(n):
            raise ModelFileError(file, lines.get(n, 0), f"body name `{n}` is not an identifier (letters, digits, `_`)")
    for attr in ("dof_damping", "dof_armature", "dof_frictionloss", "jnt_stiffness"):
        if np.any(getattr(model, attr) != 0):
            raise ModelFileError(
                file,
                0,
                f"joint {attr.split('_', 1)[1]} is beyond the subset (the scenario language has none; set it to 0)",
            )
    links = []
    for b in range(model.nbody):
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.body_iquat[b])
        r = rot.reshape(3, 3)
        tensor = r @ np.diag(model.body_inertia[b]) @ r.T
        shapes = []
        for g in range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b]):
            shape = _shape(int(model.geom_type[g]), model.geom_size[g], file, model.geom(g).name or f"geom_{g}")
            rgba = model.geom_rgba[g]
            color = (float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3]))
            shapes.append(PlacedShape(shape, vec(model.geom_pos[g]), quat4(model.geom_quat[g]), color))
        mass = 0.0 if b == 0 else float(model.body_mass[b])
        links.append(
            LinkDesc(
                names[b],
                mass,
                vec(model.body_ipos[b]),
                (vec(tensor[0]), vec(tensor[1]), vec(tensor[2])),
                vec(data.xpos[b]),
                quat4(data.xquat[b]),
                tuple(shapes),
                None,
                lines.get(names[b], 0),
            )
        )
    joints = []
    for b in range(1, model.nbody):
        parent = names[int(model.body_parentid[b])]
        count = int(model.body_jntnum[b])
        first = int(model.body_jntadr[b])
        kinds = [int(model.jnt_type[j]) for j in range(first, first + count)]
        whole = None  # a body welded to its parent (no joint), or free (a free joint is no joint)
        if count == 0:
            whole = (f"{names[b]}_weld", "fixed")
        elif kinds == [int(mujoco.mjtJoint.mjJNT_FREE)]:
            whole = (model.joint(first).name or f"{names[b]}_free", "free")
        if whole is not None:
            joints.append(JointDesc(whole[0], whole[1], parent, names[b], (1.0, 0.0, 0.0), vec(data.xpos[b]), None,
                                    None, lines.get(names[b], 0)))  # fmt: skip
            continue
        if count != 1 or kinds[0] not in _JOINTS:
            raise ModelFileError(
                file,
                lines.get(names[b], 0),
                f"body `{names[b]}` has joints beyond the subset (one hinge or slide per body, or one free joint)",
            )
        j = first
        jname = model.joint(j).name or f"{names[b]}_joint"
        lo, hi = (float(model.jnt_range[j][0]), float(model.jnt_range[j][1])) if model.jnt_limited[j] else (None, None)
        joints.append(
            JointDesc(
                jname,
                _JOINTS[kinds[0]],
                parent,
                names[b],
                vec(data.xaxis[j]),
                vec(data.xanchor[j]),
                lo,
                hi,
                lines.get(jname, 0),
            )
        )
    return ModelDesc(str(file), "worldbody", tuple(links), tuple(joints))
