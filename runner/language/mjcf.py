"""Read an MJCF file into a :class:`~runner.language.robot_desc.ModelDesc`, through MuJoCo's own compiler.

Why MuJoCo's compiler: `<include>`, default classes, `<asset>` meshes, `<compiler>` (angle, eulerseq,
meshdir, inertiafromgeom, balanceinertia...), `fromto` and frame composition are MuJoCo's semantics; only
MuJoCo computes them exactly. So whatever MuJoCo accepts is read (a file MuJoCo refuses is refused with its
message and line), and the compiled model is mapped into the engine-neutral description:

- every body a link (the world body is the static link `worldbody`), its mass, centre of mass and inertia
  as MuJoCo computed them; every geom that can collide (contype or conaffinity non-zero, and the file's
  `<flag contact>` not disabled) a shape: primitives as they are, an ellipsoid and a mesh as a convex hull
  (docs/robots.md, MJCF);
- every joint (hinge, slide, ball, free); a body without a joint is welded to its parent;
- body pairs MuJoCo never lets touch (contype/conaffinity of all their geoms, `<exclude>`) are excluded;
- actuators are listed (the robot's controllable joints);
- every hinge's and slide's damping, friction loss, armature and stiffness (:class:`JointDynamics`);
- several joints in one body, in order (every engine: a chain of light bodies where MuJoCo is not the engine,
  backends/_kit/chains.py);
- tendons and equalities (runner.language.mjcf_needs): a tendon without a force of its own is inert (a note);
  an equality that couples two hinges or slides linearly is a mimic (``JointDesc.mimic``, `joint:mimic`);
- `<option density viscosity wind>`: MuJoCo's inertia-box fluid model (:attr:`ModelDesc.fluid`), run by the
  runner's forces where MuJoCo is not the engine (runner.sim.fluid);
- what only an engine that reads the file itself can run (a tendon that acts, any other `<equality>`, a ball
  joint's dynamics, explicit contact pairs, a massless moving body, per-geom ellipsoid fluid forces) is recorded in
  :attr:`ModelDesc.needs` as capabilities, with what needs it at its line: MuJoCo, which builds the robot from
  the file (backends/mujoco), runs it; another engine refuses it before the run. Armature and stiffness are
  named there too (`joint:armature`, `joint:stiffness`), so that an engine without them refuses at their line.

Named sites become frames on their bodies (``ModelDesc.frames``: readable, never simulated); cameras, lights,
`<custom>`, `<sensor>`, `<visual>`, `<statistic>` do not change the dynamics of a step
and are not read; `<keyframe>`s are read as start states a scenario may pick (`initial: {keyframe: NAME}`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from backends.types import NO_DYNAMICS, JointDynamics, Mesh, PlacedShape, Shape, ShapeKind
from runner.language.mesh_limits import check_mesh_file
from runner.language.mjcf_legacy import Upgraded, upgrade
from runner.language.mjcf_needs import first_line, read_needs
from runner.language.model_names import check_names
from runner.language.model_numbers import check_mjcf_numbers, check_number, check_vertices
from runner.language.robot_desc import (
    ActuatorDesc,
    FrameDesc,
    JointDesc,
    KeyframeDesc,
    LinkDesc,
    ModelDesc,
    ModelFileError,
    quat4,
    resolved,
    vec,
)
from runner.language.urdf_xml import parse_xml
from runner.language.visuals import mjcf_visuals, within_budget

_JOINTS = {0: "free", 1: "ball", 2: "slider", 3: "hinge"}  # mjtJoint
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


def compile_file(file: Path, legacy: Upgraded | None = None) -> Any:
    """MuJoCo's compiled model of ``file``, or of its upgrade from MJCF's legacy dialect (ModelFileError with
    MuJoCo's message and line when it refuses)."""
    mujoco = _mujoco(file)
    try:
        if legacy is None:
            return mujoco.MjModel.from_xml_path(str(file))
        includes = {name: Path(path).read_bytes() for name, path in legacy.includes}
        spec = mujoco.MjSpec.from_string(legacy.text, include=includes or None)
        spec.modelfiledir = str(file.parent)  # meshes and textures relative to the file, as from the file
        return spec.compile()
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
        check_names(file, kind, [(n, lines.get((kind, n), 0)) for n in names])
    return bodies, joints


def _dynamics(model: Any, j: int) -> JointDynamics:
    """A hinge's or slide's damping, friction loss, armature and spring as MuJoCo compiled them (defaults
    applied); the spring's rest position from the zero configuration (``qpos_spring - qpos0``)."""
    if int(model.jnt_type[j]) not in (2, 3):
        return NO_DYNAMICS
    dof, q = int(model.jnt_dofadr[j]), int(model.jnt_qposadr[j])
    return JointDynamics(
        damping=float(model.dof_damping[dof]),
        frictionloss=float(model.dof_frictionloss[dof]),
        armature=float(model.dof_armature[dof]),
        stiffness=float(model.jnt_stiffness[j]),
        springref=float(model.qpos_spring[q] - model.qpos0[q]),
    )


def _welded(model: Any, a: int, b: int) -> bool:
    """MuJoCo's parent filter (mj_collision), unless the file disables it (`<flag filterparent="disable"/>`)."""
    import mujoco  # loaded: the model is MuJoCo's

    wa, wb = int(model.body_weldid[a]), int(model.body_weldid[b])
    if wa == wb:
        return True
    if int(model.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT) or not (wa and wb):
        return False
    pa, pb = int(model.body_weldid[model.body_parentid[wa]]), int(model.body_weldid[model.body_parentid[wb]])
    return wa == pb or wb == pa


def _excluded(model: Any, bodies: list[str]) -> list[tuple[str, str]]:
    """Body pairs (both with collision shapes) that MuJoCo never lets touch: no geom pair passes the
    contype/conaffinity test, MuJoCo's parent filter (on the bodies' weld roots, ``body_weldid``: two bodies
    welded together, or one welded group the parent of the other, neither the world's: humanoid_CMU's neck
    and head overlap across a weld), or an `<exclude>` names them."""
    masks: dict[int, list[tuple[int, int]]] = {}
    for g in range(model.ngeom):
        t, a = int(model.geom_contype[g]), int(model.geom_conaffinity[g])
        if t or a:
            masks.setdefault(int(model.geom_bodyid[g]), []).append((t, a))
    out = []
    ids = sorted(masks)
    for i, a in enumerate(ids):
        for b in ids[i + 1 :]:
            if not any(ta & ab or tb & aa for ta, aa in masks[a] for tb, ab in masks[b]) or _welded(model, a, b):
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
        if joint is not None and int(model.jnt_type[int(model.actuator_trnid[a][0])]) not in (2, 3):
            joint = None  # a ball or free joint's actuator: several coordinates, MuJoCo's alone
        line = next((v for (tag, n), v in lines.items() if n == name and tag != "joint" and tag != "body"), 0)
        trn = mujoco.mjtTrn(int(model.actuator_trntype[a])).name.removeprefix("mjTRN_").lower()
        unmapped = None
        if joint is None:
            unmapped = f"a {trn} transmission"
        elif key[2] != 0:
            unmapped = "activation dynamics (`dyntype`)"
        elif key[0] != 0 or key[1] not in (0, 1):
            unmapped = "a gain or bias that is not fixed or affine"
        limited = bool(model.actuator_ctrllimited[a]), bool(model.actuator_forcelimited[a])
        out.append(
            ActuatorDesc(
                name, kind, joint, line,
                gear=float(model.actuator_gear[a][0]),
                gain=float(model.actuator_gainprm[a][0]),
                bias=(float(model.actuator_biasprm[a][0]), float(model.actuator_biasprm[a][1]),
                      float(model.actuator_biasprm[a][2])),
                ctrlrange=(float(model.actuator_ctrlrange[a][0]), float(model.actuator_ctrlrange[a][1]))
                if limited[0] else None,
                forcerange=(float(model.actuator_forcerange[a][0]), float(model.actuator_forcerange[a][1]))
                if limited[1] else None,
                unmapped=unmapped,
            )
        )  # fmt: skip
    return out


#: included files followed when looking for meshes (MuJoCo refuses a file that includes itself)
MAX_INCLUDES = 64


def _check_meshes(tree: Any, file: Path) -> None:
    """Every `<mesh file=...>` of the file and of the files it includes (their numbers checked too) within the
    mesh limits, before MuJoCo reads them (runner.language.mesh_limits); a file that cannot be found or read
    is left to MuJoCo's own message."""
    compiler = tree.getroot().find("compiler")
    folder = file.parent
    if compiler is not None:
        folder = folder / (compiler.get("meshdir") or compiler.get("assetdir") or "")
    todo, seen = [(tree, file)], {file.resolve()}
    while todo:
        current, owner = todo.pop()
        for element in current.getroot().iter("mesh", "include"):
            name, line = element.get("file"), element.sourceline or 0
            if not name:
                continue
            base = folder if element.tag == "mesh" else file.parent  # includes are relative to the main file
            path = resolved(base / name, owner, line, name)
            if element.tag == "mesh" and path.is_file():
                check_mesh_file(path, owner, line, name)
            elif element.tag == "include" and path.is_file() and path not in seen and len(seen) < MAX_INCLUDES:
                seen.add(path)
                included = parse_xml(path)
                check_mjcf_numbers(included, path)
                todo.append((included, path))


def _check_compiled(model: Any, file: Path, bodies: list[str], lines: dict[tuple[str, str], int]) -> None:
    """What MuJoCo computed (defaults, includes and `fromto` applied) finite and within +-MAX_MAGNITUDE, at
    the body's line: the main file's attributes were checked one by one before (check_mjcf_numbers)."""
    for b in range(1, model.nbody):
        geoms = range(int(model.body_geomadr[b]), int(model.body_geomadr[b]) + int(model.body_geomnum[b]))
        fields = {"pos": model.body_pos[b], "quat": model.body_quat[b], "mass": [model.body_mass[b]],
                  "inertia": model.body_inertia[b], "geom size": [v for g in geoms for v in model.geom_size[g]],
                  "geom pos": [v for g in geoms for v in model.geom_pos[g]]}  # fmt: skip
        for what, values in fields.items():
            for value in np.asarray(values, dtype=float).ravel():
                problem = check_number(float(value), "any")
                if problem is not None:
                    raise ModelFileError(file, lines.get(("body", bodies[b]), 0),
                                         f"body `{bodies[b]}`: its {what} {float(value)!r} {problem}")  # fmt: skip
    if model.nmeshvert:
        line = next((line for (tag, _), line in lines.items() if tag == "mesh"), 0)
        check_vertices(np.asarray(model.mesh_vert), file, line, "of the model")


def _keyframes(model: Any, joints: list[str], tree: Any) -> list[KeyframeDesc]:
    """The file's keys: hinge and slide values from the zero configuration (qpos0), and the other joints
    they move."""
    keys = list(tree.getroot().iter("key"))
    out = []
    for k in range(model.nkey):
        name = model.key(k).name or f"key_{k}"
        values, others = [], []
        for j in range(model.njnt):
            q, d = int(model.jnt_qposadr[j]), int(model.jnt_dofadr[j])
            kind = _JOINTS[int(model.jnt_type[j])]
            if kind in ("hinge", "slider"):
                values.append((joints[j], float(model.key_qpos[k][q] - model.qpos0[q]), float(model.key_qvel[k][d])))
                continue
            nq, nv = (7, 6) if kind == "free" else (4, 3)
            moved = np.any(model.key_qpos[k][q : q + nq] != model.qpos0[q : q + nq])
            if moved or np.any(model.key_qvel[k][d : d + nv]):
                others.append(joints[j])
        line = (keys[k].sourceline or 0) if k < len(keys) else 0
        out.append(KeyframeDesc(name, line, tuple(values), tuple(others)))
    return out


def load_mjcf(file: Path) -> ModelDesc:
    tree = parse_xml(file)
    check_mjcf_numbers(tree, file)
    _check_meshes(tree, file)
    mujoco = _mujoco(file)
    legacy = upgrade(file)
    model = compile_file(file, legacy)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    lines = _lines(tree)
    bodies, joint_names = _names(model, file, lines)
    _check_compiled(model, file, bodies, lines)
    touchless = _contacts_disabled(model, mujoco)
    links = []
    for b in range(model.nbody):
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.body_iquat[b])
        r = rot.reshape(3, 3)
        tensor = r @ np.diag(model.body_inertia[b]) @ r.T
        shapes = []
        for g in range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b]):
            if touchless or not (model.geom_contype[g] or model.geom_conaffinity[g]):
                continue  # a visual geom (or contacts off in the file): it never touches anything
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
    start: list[tuple[str, float]] = []
    notes: list[str] = list(legacy.notes) if legacy is not None else []
    found = read_needs(model, mujoco, tree, bodies, joint_names, lines)
    notes.extend(_flag_notes(model, mujoco, first_line(tree, "flag")))
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
            zero = float(model.qpos0[int(model.jnt_qposadr[j])]) if limited else 0.0  # `ref`: the file's pose
            lo, hi = (None, None) if not limited else (float(model.jnt_range[j][0]) - zero,
                                                       float(model.jnt_range[j][1]) - zero)  # fmt: skip
            if lo is not None and hi is not None and not lo <= 0.0 <= hi:  # ant's ankles: range="30 100"
                begin = lo if lo > 0.0 else hi
                start.append((joint_names[j], begin))
                notes.append(f"joint `{joint_names[j]}`: its zero (the file's pose) is outside its range [{lo:g}, "
                             f"{hi:g}]; it starts at {begin:g}, the nearest end (MuJoCo would start it outside "
                             f"and the limit would throw it)")  # fmt: skip
            anchor = vec(data.xanchor[j]) if kind != "free" else vec(data.xpos[b])
            joints.append(JointDesc(joint_names[j], kind, parent, bodies[b], vec(data.xaxis[j]), anchor, lo, hi,
                                    lines.get(("joint", joint_names[j]), line), _dynamics(model, j),
                                    found.mimics.get(joint_names[j])))  # fmt: skip
    return ModelDesc(
        str(file),
        "worldbody",
        tuple(within_budget(links)),
        tuple(joints),
        notes=tuple(notes + found.notes),
        needs=tuple(found.needs),
        actuators=tuple(_actuators(model, joint_names, lines, mujoco)),
        excluded=tuple(_excluded(model, bodies)),
        timestep=float(model.opt.timestep),
        gravity=vec(model.opt.gravity),
        keyframes=tuple(_keyframes(model, joint_names, tree)),
        frames=tuple(_sites(model, bodies, set(joint_names))),
        start=tuple(start),
        upgraded=(legacy.text, legacy.includes) if legacy is not None else None,
        fluid=found.fluid,
    )


def _contacts_disabled(model: Any, mujoco: Any) -> bool:
    """`<option><flag contact="disable"/>` (or `constraint="disable"`, which turns contacts off with every other
    constraint): MuJoCo detects no contact at all in the file's model (dm_control's reacher, pendulum, cartpole,
    point_mass, swimmer; acrobot, lqr, fish), so none of its geoms is a collision shape on any engine, with the
    scenario's options (MuJoCo's backend then zeroes their contype and conaffinity, backends/mujoco). It is part
    of the model: without it reacher's arm starts 0.06 m deep in its target sphere and root cylinder, with
    contact normals no joint can move along (docs/robots.md, "MJCF as MuJoCo reads it")."""
    off = int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    return bool(int(model.opt.disableflags) & off)


#: `<flag>` settings read as part of the model (the rest are simulation options: MuJoCo's own with `options:
#: model`, not applied with the scenario's options, where the world's gravity and the engine's solver act)
_MODEL_FLAGS = ("contact", "constraint")


def _flag_notes(model: Any, mujoco: Any, line: int) -> list[str]:
    """What the file's `<flag>` disable settings become (docs/robots.md, "MJCF as MuJoCo reads it")."""
    flags = int(model.opt.disableflags)
    named = [n.removeprefix("mjDSBL_").lower() for n in dir(mujoco.mjtDisableBit) if n.startswith("mjDSBL_")]
    off = sorted(n for n in named if flags & int(getattr(mujoco.mjtDisableBit, f"mjDSBL_{n.upper()}")))
    out = []
    kept = [n for n in off if n in _MODEL_FLAGS]
    if kept:
        out.append(f"`<flag {kept[0]}=\"disable\"/>` (line {line}): the file's geoms touch nothing, as MuJoCo runs "
                   "it (its shapes are drawn, not collided)")  # fmt: skip
    rest = [n for n in off if n not in _MODEL_FLAGS and n not in ("autoreset", "filterparent")]
    if rest:
        out.append("with the scenario's options, the file's " + ", ".join(f'`<flag {n}="disable"/>`' for n in rest)
                   + f" (line {line}) not applied: the world's gravity and the engine's own solver act (MuJoCo "
                   "runs them with `world: {options: model}`)")  # fmt: skip
    return out


def _sites(model: Any, bodies: list[str], joints: set[str]) -> list[FrameDesc]:
    """Every named site as a frame on its body (as MuJoCo compiled its pose in the body frame); a site named as
    a body or joint is left out (the body or joint keeps the name)."""
    taken = set(bodies) | joints
    out = []
    for i in range(model.nsite):
        name = model.site(i).name
        if name and name not in taken:
            out.append(
                FrameDesc(name, bodies[int(model.site_bodyid[i])], vec(model.site_pos[i]), quat4(model.site_quat[i]))
            )
    return out
